//! Mesh files: PLY (ASCII, binary little and big endian) and OBJ (`v` and `f`), read into
//! vertex positions and fan-triangulated faces, then placed by a [`MeshTransform`] and rounded
//! to f32.
//!
//! Both readers are written here rather than taken from a crate; measured on the bunny cut into
//! 1,061,786 triangles (scenes/models/make_large_mesh.py) on 2 cores, 2026-11-24:
//!
//! * `ply-rs` 0.1.3 reads the 21 MB binary PLY in 0.63 s (this reader, with the placement, in
//!   0.23 – 0.25 s): it builds a key-value map per vertex and per face, cloning each property's
//!   name into it. A truncated file is "failed to fill whole buffer", with no element or offset,
//!   and nothing compares the header's counts with the file's size.
//! * `tobj` 4 reads the same mesh as a 61 MB OBJ in 0.46 – 0.48 s (this reader 0.35 – 0.55 s), but
//!   an index out of range (or 0) is `FaceVertexOutOfBounds` without the line, a face of two
//!   vertices becomes a degenerate triangle instead of an error, and coordinates are parsed as
//!   f32 (every value as f64 only with a feature), where the scene format asks for the file's
//!   decimals in f64, rounded to f32 once after the transform.
//!
//! The readers here check the header's counts against the bytes that follow before reading,
//! never reserve more than those bytes can hold, and name the face and the line (ASCII, OBJ) or
//! byte offset (binary PLY) of every defect.

use super::format::{MeshDesc, MeshTransform};
use std::fmt;
use std::path::{Path, PathBuf};

/// A mesh as its file gives it: positions in f64 and triangles (faces fanned) as indices.
#[derive(Debug, Clone, Default)]
pub struct MeshData {
    pub positions: Vec<[f64; 3]>,
    /// Triangles, as indices into `positions` (checked in range).
    pub triangles: Vec<[u32; 3]>,
    /// The face of the file each triangle comes from (0-based), for messages.
    pub face_of: Vec<u32>,
    /// Number of faces in the file.
    pub faces: usize,
}

/// What is wrong with a mesh file, and what to do about it.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshError {
    pub message: String,
    pub help: String,
}

impl fmt::Display for MeshError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} (help: {})", self.message, self.help)
    }
}

fn err(message: impl Into<String>, help: impl Into<String>) -> MeshError {
    MeshError {
        message: message.into(),
        help: help.into(),
    }
}

/// A mesh placed in the scene: its triangles' vertices in f32, and what was dropped.
#[derive(Debug, Clone, Default)]
pub struct LoadedMesh {
    /// The file, as the scene names it.
    pub file: String,
    /// Its path on disk (relative to the scene's folder when the scene path is relative).
    pub path: PathBuf,
    pub material: String,
    pub triangles: Vec<[[f32; 3]; 3]>,
    pub vertices: usize,
    pub faces: usize,
    /// Triangles with zero area at f32 precision, dropped.
    pub dropped: usize,
    /// The file's face (0-based) of the first dropped triangle.
    pub first_dropped_face: Option<u32>,
}

/// Reads a mesh file's bytes; the format is chosen by the extension (`.ply`, `.obj`, any case),
/// else by a leading `ply` line.
pub fn parse(name: &str, bytes: &[u8]) -> Result<MeshData, MeshError> {
    let ext = Path::new(name)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("ply") => parse_ply(bytes),
        Some("obj") => parse_obj(bytes),
        _ if bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n") => parse_ply(bytes),
        _ => Err(err(
            "unknown mesh format",
            "mesh files are PLY (.ply) or Wavefront OBJ (.obj)",
        )),
    }
}

/// Places `data` by `transform`, rounds to f32, checks every vertex is finite and drops the
/// triangles of zero area in f32 (counted).
pub fn place(
    desc: &MeshDesc,
    path: PathBuf,
    data: &MeshData,
    transform: &MeshTransform,
) -> Result<LoadedMesh, MeshError> {
    let mut placed: Vec<[f32; 3]> = Vec::with_capacity(data.positions.len());
    for (k, v) in data.positions.iter().enumerate() {
        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
            return Err(err(
                format!("vertex {k} has a coordinate {x} (not finite) in the file"),
                "every vertex coordinate must be a finite number; fix or remove the vertex",
            ));
        }
        let p = transform.apply(*v).map(|x| x as f32);
        let limit = super::validate::MAX_COORDINATE;
        if p.iter()
            .any(|x| !x.is_finite() || f64::from(x.abs()) > limit)
        {
            return Err(err(
                format!(
                    "vertex {k} ({}, {}, {}) is beyond +-{limit:e} after the scale, rotation \
                     and translation, where squared distances overflow 32-bit floats",
                    v[0], v[1], v[2]
                ),
                "the renderer computes in f32: use a smaller scale or translation",
            ));
        }
        placed.push(p);
    }
    let mut triangles = Vec::with_capacity(data.triangles.len());
    let (mut dropped, mut first_dropped_face) = (0, None);
    for (t, &face) in data.triangles.iter().zip(&data.face_of) {
        let v = t.map(|i| placed[i as usize]);
        if super::validate::degenerate_f32(v) {
            dropped += 1;
            first_dropped_face.get_or_insert(face);
        } else {
            triangles.push(v);
        }
    }
    if triangles.is_empty() {
        return Err(err(
            if data.triangles.is_empty() {
                "the mesh has no faces".to_string()
            } else {
                format!(
                    "all {} triangles of the mesh have zero area at f32 precision",
                    data.triangles.len()
                )
            },
            "give the mesh faces of nonzero area, or remove it from `meshes`",
        ));
    }
    Ok(LoadedMesh {
        file: desc.file.clone(),
        path,
        material: desc.material.clone(),
        triangles,
        vertices: data.positions.len(),
        faces: data.faces,
        dropped,
        first_dropped_face,
    })
}

/// Collects triangles as faces are read: fans each polygon (v0, v_i, v_i+1).
struct Faces {
    triangles: Vec<[u32; 3]>,
    face_of: Vec<u32>,
    faces: usize,
}

impl Faces {
    fn with_capacity(n: usize) -> Faces {
        Faces {
            triangles: Vec::with_capacity(n),
            face_of: Vec::with_capacity(n),
            faces: 0,
        }
    }
    /// Adds one triangle of the fan of face `self.faces`.
    fn fan(&mut self, first: u32, prev: u32, next: u32) {
        self.triangles.push([first, prev, next]);
        self.face_of.push(self.faces as u32);
    }
    fn into_data(self, positions: Vec<[f64; 3]>) -> MeshData {
        MeshData {
            positions,
            triangles: self.triangles,
            face_of: self.face_of,
            faces: self.faces,
        }
    }
}

fn too_few(face: usize, n: u64, at: &str) -> MeshError {
    err(
        format!("face {face}{at} has {n} vertices; a face needs at least 3"),
        "remove the face, or give it three or more vertices",
    )
}

fn out_of_range(face: usize, index: i64, vertices: usize, at: &str) -> MeshError {
    err(
        format!(
            "face {face}{at}: vertex index {index} is out of range (the file has {vertices} \
             vertices)"
        ),
        "indices must name vertices of the file; check the face and the vertex count",
    )
}

// ---------------------------------------------------------------------------------------------
// PLY

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
    fn is_int(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Debug)]
enum Prop {
    Scalar(Scalar),
    /// A list: its count's type and its items' type.
    List(Scalar, Scalar),
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<(String, Prop)>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Format {
    Ascii,
    Little,
    Big,
}

const PLY_HELP: &str = "the PLY header is `ply`, `format ascii|binary_little_endian|\
     binary_big_endian 1.0`, then `element` and `property` lines, then `end_header`";

/// Parses the header; returns the format, the elements and the offset of the body.
fn ply_header(bytes: &[u8]) -> Result<(Format, Vec<Element>, usize), MeshError> {
    let mut pos = 0;
    let mut line_no = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(err(
                "the PLY header has no `end_header` line",
                "the file may be truncated or not a PLY file",
            ));
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        line_no += 1;
        let line = std::str::from_utf8(raw)
            .map_err(|_| err(format!("header line {line_no} is not text"), PLY_HELP))?
            .trim_end_matches('\r');
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        let bad = || {
            err(
                format!("header line {line_no} `{line}` is not understood"),
                PLY_HELP,
            )
        };
        if line_no == 1 {
            if line.trim() != "ply" {
                return Err(err("the file does not start with `ply`", PLY_HELP));
            }
            continue;
        }
        match words.as_slice() {
            [] => {}
            ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, _version] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    _ => return Err(bad()),
                })
            }
            ["element", name, count] => {
                let count: u64 = count.parse().map_err(|_| bad())?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", "list", c, i, name] => {
                let (Some(c), Some(i)) = (Scalar::from_name(c), Scalar::from_name(i)) else {
                    return Err(bad());
                };
                if !c.is_int() {
                    return Err(err(
                        format!("header line {line_no}: a list's count must be an integer type"),
                        PLY_HELP,
                    ));
                }
                let e = elements.last_mut().ok_or_else(bad)?;
                e.props.push((name.to_string(), Prop::List(c, i)));
            }
            ["property", t, name] => {
                let t = Scalar::from_name(t).ok_or_else(bad)?;
                let e = elements.last_mut().ok_or_else(bad)?;
                e.props.push((name.to_string(), Prop::Scalar(t)));
            }
            ["end_header"] => break,
            _ => return Err(bad()),
        }
    }
    let format = format.ok_or_else(|| err("the PLY header has no `format` line", PLY_HELP))?;
    Ok((format, elements, pos))
}

/// The vertex element's x, y and z columns.
fn xyz_columns(e: &Element) -> Result<[usize; 3], MeshError> {
    let mut cols = [usize::MAX; 3];
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        match e.props.iter().position(|(n, _)| n == name) {
            Some(i) if matches!(e.props[i].1, Prop::Scalar(_)) => cols[k] = i,
            _ => {
                return Err(err(
                    format!("the `vertex` element has no scalar property `{name}`"),
                    "a PLY mesh's vertices need properties x, y and z",
                ))
            }
        }
    }
    Ok(cols)
}

fn face_column(e: &Element) -> Result<usize, MeshError> {
    e.props
        .iter()
        .position(|(n, p)| {
            (n == "vertex_indices" || n == "vertex_index") && matches!(p, Prop::List(..))
        })
        .ok_or_else(|| {
            err(
                "the `face` element has no list property `vertex_indices`",
                "a PLY mesh's faces are `property list uchar int vertex_indices`",
            )
        })
}

/// Reads values from the body of a PLY file: binary (either byte order) or ASCII tokens.
struct Body<'a> {
    bytes: &'a [u8],
    pos: usize,
    format: Format,
    /// ASCII: the 1-based line of `pos`.
    line: usize,
}

enum Value {
    Int(i64),
    Float(f64),
}

impl Value {
    fn as_f64(&self) -> f64 {
        match *self {
            Value::Int(i) => i as f64,
            Value::Float(x) => x,
        }
    }
}

impl<'a> Body<'a> {
    /// Where the reader is, for messages.
    fn at(&self) -> String {
        match self.format {
            Format::Ascii => format!(" (line {})", self.line),
            _ => format!(" (byte {})", self.pos),
        }
    }

    fn truncated(&self, what: &str) -> MeshError {
        err(
            format!("the file ends inside {what}{}", self.at()),
            "the file is truncated: export or download it again",
        )
    }

    fn take(&mut self, n: usize, what: &dyn Fn() -> String) -> Result<&'a [u8], MeshError> {
        if self.bytes.len() - self.pos < n {
            return Err(self.truncated(&what()));
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn token(&mut self, what: &dyn Fn() -> String) -> Result<&'a str, MeshError> {
        let b = self.bytes;
        while self.pos < b.len() && b[self.pos].is_ascii_whitespace() {
            if b[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < b.len() && !b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if start == self.pos {
            return Err(self.truncated(&what()));
        }
        std::str::from_utf8(&b[start..self.pos]).map_err(|_| {
            err(
                format!("{} is not a number{}", what(), self.at()),
                "an ASCII PLY's body holds numbers separated by white space",
            )
        })
    }

    fn read(&mut self, t: Scalar, what: &dyn Fn() -> String) -> Result<Value, MeshError> {
        if self.format == Format::Ascii {
            let tok = self.token(what)?;
            let bad = || {
                err(
                    format!(
                        "{} `{tok}` is not a number of type {t:?}{}",
                        what(),
                        self.at()
                    ),
                    "an ASCII PLY's body holds numbers separated by white space",
                )
            };
            return if t.is_int() {
                tok.parse::<i64>().map(Value::Int).map_err(|_| bad())
            } else {
                tok.parse::<f64>().map(Value::Float).map_err(|_| bad())
            };
        }
        let b = self.take(t.size(), what)?;
        let big = self.format == Format::Big;
        macro_rules! num {
            ($ty:ty) => {{
                let a = b.try_into().unwrap();
                if big {
                    <$ty>::from_be_bytes(a)
                } else {
                    <$ty>::from_le_bytes(a)
                }
            }};
        }
        Ok(match t {
            Scalar::I8 => Value::Int(b[0] as i8 as i64),
            Scalar::U8 => Value::Int(b[0] as i64),
            Scalar::I16 => Value::Int(num!(i16) as i64),
            Scalar::U16 => Value::Int(num!(u16) as i64),
            Scalar::I32 => Value::Int(num!(i32) as i64),
            Scalar::U32 => Value::Int(num!(u32) as i64),
            // f32 to f64 is exact: the file's value, unrounded.
            Scalar::F32 => Value::Float(num!(f32) as f64),
            Scalar::F64 => Value::Float(num!(f64)),
        })
    }

    /// Reads a list's length.
    fn count(&mut self, t: Scalar, what: &dyn Fn() -> String) -> Result<u64, MeshError> {
        match self.read(t, what)? {
            Value::Int(n) if n >= 0 => Ok(n as u64),
            Value::Int(n) => Err(err(
                format!("{} has a negative length {n}{}", what(), self.at()),
                "the file is damaged",
            )),
            Value::Float(_) => unreachable!("list counts are integers"),
        }
    }

    /// Skips a property's value(s).
    fn skip(&mut self, p: &Prop, what: &dyn Fn() -> String) -> Result<(), MeshError> {
        match *p {
            Prop::Scalar(t) => {
                self.read(t, what)?;
            }
            Prop::List(c, i) => {
                let n = self.count(c, what)?;
                if self.format != Format::Ascii {
                    let bytes = n.saturating_mul(i.size() as u64);
                    if bytes > (self.bytes.len() - self.pos) as u64 {
                        return Err(self.truncated(&what()));
                    }
                    self.pos += bytes as usize;
                } else {
                    for _ in 0..n {
                        self.read(i, what)?;
                    }
                }
            }
        }
        Ok(())
    }
}

/// The fewest bytes one instance of `e` takes in the body: binary, lists empty; ASCII, one
/// digit and one separator per value.
fn min_record(e: &Element, format: Format) -> u64 {
    e.props
        .iter()
        .map(|(_, p)| match (format, p) {
            (Format::Ascii, _) => 2,
            (_, Prop::Scalar(t)) => t.size() as u64,
            (_, Prop::List(c, _)) => c.size() as u64,
        })
        .sum()
}

fn parse_ply(bytes: &[u8]) -> Result<MeshData, MeshError> {
    let (format, elements, body_start) = ply_header(bytes)?;
    let vertex = elements
        .iter()
        .find(|e| e.name == "vertex")
        .ok_or_else(|| {
            err(
                "the PLY file has no `vertex` element",
                "a PLY mesh needs `element vertex N` with x, y, z properties",
            )
        })?;
    let face = elements.iter().find(|e| e.name == "face").ok_or_else(|| {
        err(
            "the PLY file has no `face` element",
            "a PLY mesh needs `element face N` with a list property vertex_indices (point \
             clouds are not meshes)",
        )
    })?;
    let xyz = xyz_columns(vertex)?;
    let face_col = face_column(face)?;
    let n_vertices = vertex.count;

    // The header's counts against the file's size: every element takes at least min_record
    // bytes per instance, so counts the rest of the file cannot hold are refused before any
    // memory is reserved for them.
    let left = (bytes.len() - body_start) as u64;
    let mut need: u64 = 0;
    for e in &elements {
        need = need.saturating_add(e.count.saturating_mul(min_record(e, format)));
    }
    // ASCII: the last value needs no separator after it.
    let slack = u64::from(format == Format::Ascii);
    if need > left + slack {
        let counts: Vec<String> = elements
            .iter()
            .map(|e| format!("{} {}", e.count, e.name))
            .collect();
        return Err(err(
            format!(
                "the header's counts ({}) need at least {need} bytes, but only {left} bytes \
                 follow the header",
                counts.join(", ")
            ),
            "the file is truncated or its header is wrong: export or download it again",
        ));
    }

    if n_vertices > u32::MAX as u64 {
        return Err(err(
            format!("{n_vertices} vertices are more than 2^32 - 1"),
            "split the mesh into several files",
        ));
    }

    let mut body = Body {
        bytes,
        pos: body_start,
        format,
        line: bytes[..body_start].iter().filter(|&&b| b == b'\n').count() + 1,
    };
    // Never more than the file can hold (checked above), and never from a count alone.
    let cap = |e: &Element| e.count.min(left / min_record(e, format).max(1)) as usize;
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut faces = Faces::with_capacity(0);
    for e in &elements {
        let is_vertex = std::ptr::eq(e, vertex);
        let is_face = std::ptr::eq(e, face);
        if is_vertex {
            positions.reserve_exact(cap(e));
        }
        if is_face {
            faces = Faces::with_capacity(cap(e));
        }
        for k in 0..e.count {
            let what = || format!("{} {k} of {}", e.name, e.count);
            if is_vertex {
                let mut p = [0.0; 3];
                for (col, (_, prop)) in e.props.iter().enumerate() {
                    match (xyz.iter().position(|&c| c == col), prop) {
                        (Some(axis), Prop::Scalar(t)) => p[axis] = body.read(*t, &what)?.as_f64(),
                        _ => body.skip(prop, &what)?,
                    }
                }
                positions.push(p);
            } else if is_face {
                for (col, (_, prop)) in e.props.iter().enumerate() {
                    match prop {
                        Prop::List(c, i) if col == face_col => {
                            read_face(&mut body, &mut faces, (*c, *i), n_vertices, (k, e.count))?
                        }
                        _ => body.skip(prop, &what)?,
                    }
                }
                faces.faces += 1;
            } else {
                for (_, prop) in &e.props {
                    body.skip(prop, &what)?;
                }
            }
        }
    }
    Ok(faces.into_data(positions))
}

/// Reads face `face.0` of `face.1`, a list of (count type, index type) `types`.
fn read_face(
    body: &mut Body,
    faces: &mut Faces,
    (count_type, index_type): (Scalar, Scalar),
    n_vertices: u64,
    (face, of): (u64, u64),
) -> Result<(), MeshError> {
    let what = || format!("face {face} of {of}");
    let face = face as usize;
    let n = body.count(count_type, &what)?;
    if n < 3 {
        return Err(too_few(face, n, &body.at()));
    }
    if body.format != Format::Ascii
        && n.saturating_mul(index_type.size() as u64) > (body.bytes.len() - body.pos) as u64
    {
        return Err(body.truncated(&what()));
    }
    let mut index = || -> Result<u32, MeshError> {
        let at = body.at();
        match body.read(index_type, &what)? {
            Value::Int(i) if i >= 0 && (i as u64) < n_vertices => Ok(i as u32),
            Value::Int(i) => Err(out_of_range(face, i, n_vertices as usize, &at)),
            Value::Float(x) => Err(err(
                format!("face {face}{at}: vertex index {x} is not an integer"),
                "a face's vertex indices must be an integer type",
            )),
        }
    };
    let first = index()?;
    let mut prev = index()?;
    for _ in 2..n {
        let next = index()?;
        faces.fan(first, prev, next);
        prev = next;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// OBJ

fn parse_obj(bytes: &[u8]) -> Result<MeshData, MeshError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        err(
            format!("the OBJ file is not UTF-8 text (byte {})", e.valid_up_to()),
            "an OBJ file is text; is this the right file?",
        )
    })?;
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut faces = Faces::with_capacity(0);
    // The largest positive index seen before its vertex existed, and its line: OBJ allows
    // forward references, so these are checked once every vertex is known.
    let mut forward: Option<(i64, usize, usize)> = None;
    for (n, raw) in text.lines().enumerate() {
        let line_no = n + 1;
        let line = raw.split('#').next().unwrap_or("");
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            Some("v") => {
                let mut p = [0.0; 3];
                for x in &mut p {
                    let w = words.next().ok_or_else(|| {
                        err(
                            format!("line {line_no}: `v` needs three coordinates"),
                            "write vertices as `v x y z`",
                        )
                    })?;
                    *x = w.parse::<f64>().map_err(|_| {
                        err(
                            format!("line {line_no}: `{w}` is not a number"),
                            "write vertices as `v x y z`",
                        )
                    })?;
                }
                positions.push(p);
            }
            Some("f") => {
                let face = faces.faces;
                let at = format!(" (line {line_no})");
                let count = positions.len() as i64;
                let mut resolved = [0u32; 2];
                let mut k = 0u64;
                for w in words {
                    let first = w.split('/').next().unwrap_or("");
                    let i: i64 = first.parse().map_err(|_| {
                        err(
                            format!("line {line_no}: `{w}` is not a vertex reference"),
                            "face entries are `i`, `i/t`, `i//n` or `i/t/n` with integer i",
                        )
                    })?;
                    let index = if i < 0 {
                        if -i > count {
                            return Err(out_of_range(face, i, count as usize, &at));
                        }
                        count + i
                    } else if i == 0 {
                        return Err(err(
                            format!("face {face}{at}: vertex index 0; OBJ counts vertices from 1"),
                            "use 1 for the first vertex, or -1 for the latest",
                        ));
                    } else {
                        if i > count && forward.is_none_or(|(m, _, _)| i > m) {
                            forward = Some((i, line_no, face));
                        }
                        i - 1
                    };
                    if index > u32::MAX as i64 {
                        return Err(out_of_range(face, i, count as usize, &at));
                    }
                    let index = index as u32;
                    match k {
                        0 | 1 => resolved[k as usize] = index,
                        _ => {
                            faces.fan(resolved[0], resolved[1], index);
                            resolved[1] = index;
                        }
                    }
                    k += 1;
                }
                if k < 3 {
                    return Err(too_few(face, k, &at));
                }
                faces.faces += 1;
            }
            _ => {}
        }
    }
    if let Some((i, line_no, face)) = forward {
        if i > positions.len() as i64 {
            return Err(out_of_range(
                face,
                i,
                positions.len(),
                &format!(" (line {line_no})"),
            ));
        }
    }
    Ok(faces.into_data(positions))
}

#[cfg(test)]
mod tests {
    use super::*;

    const QUAD_OBJ: &str = "# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\n\
                            f 1/1/1 2/1/1 3//1 -1\n";

    #[test]
    fn obj_quads_are_fanned_with_relative_indices() {
        let m = parse("q.obj", QUAD_OBJ.as_bytes()).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.face_of, vec![0, 0]);
        assert_eq!(m.faces, 1);
    }

    #[test]
    fn ascii_ply_with_extra_properties_and_elements() {
        let ply = "ply\nformat ascii 1.0\ncomment x\nelement vertex 4\nproperty float x\n\
                   property float nx\nproperty float y\nproperty double z\n\
                   element face 1\nproperty uchar red\nproperty list uchar uint vertex_indices\n\
                   element edge 1\nproperty list int int ends\nend_header\n\
                   0 9 0 0\n1 9 0 0\n1 9 1 0\n0 9 1 0.5\n7 4 0 1 2 3\n2 0 1\n";
        let m = parse("q.ply", ply.as_bytes()).unwrap();
        assert_eq!(m.positions[3], [0.0, 1.0, 0.5]);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn huge_header_counts_are_refused_before_reading() {
        let ply = "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\n\
                   property float x\nproperty float y\nproperty float z\nelement face 1\n\
                   property list uchar int vertex_indices\nend_header\n";
        let e = parse("q.ply", ply.as_bytes()).unwrap_err();
        assert!(e.message.contains("only 0 bytes follow"), "{e}");
    }
}
