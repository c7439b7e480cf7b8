//! Scenes: the JSON format, its validation, and errors that say where and what to do.

pub mod format;
pub mod locate;
pub mod mesh;
pub mod validate;

pub use format::{
    BoxDesc, CameraDesc, MaterialDesc, MeshDesc, MeshTransform, RotateDesc, Scale, SceneDesc,
    SphereDesc, TriangleDesc,
};
pub use locate::JsonPath;
pub use mesh::LoadedMesh;

use std::fmt;
use std::path::{Path, PathBuf};

/// The largest scene file read (scene files are a few kB to a few MB).
pub const MAX_SCENE_BYTES: u64 = 256 << 20;

/// The largest mesh file read: 1 GiB is about 50 million triangles of binary PLY or 20 million
/// of OBJ, beyond what 24 GiB holds once the BVH is built (140 bytes a triangle on the CPU).
pub const MAX_MESH_BYTES: u64 = 1 << 30;

/// At most `limit` bytes of a file, or None if it holds more: reads one byte past the limit, so
/// /dev/zero or a huge file is refused without reading it all.
fn read_bounded(path: &Path, limit: u64) -> std::io::Result<Option<Vec<u8>>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_end(&mut bytes)?;
    Ok((bytes.len() as u64 <= limit).then_some(bytes))
}

/// A scene that parsed and passed validation: everything the renderer needs, plus what the
/// outputs record about where it came from.
#[derive(Debug, Clone)]
pub struct Scene {
    pub desc: SceneDesc,
    /// The file it was read from (for messages and metadata).
    pub path: PathBuf,
    /// SHA-1 of the scene file's bytes followed by each mesh file's bytes in `meshes` order
    /// (for a scene without meshes, the SHA-1 of the scene file), recorded in every output so
    /// renders can be matched to scenes.
    pub sha1: String,
    /// The meshes of `desc.meshes`, read, placed and rounded to f32, in the same order.
    pub meshes: Vec<LoadedMesh>,
}

/// Why a scene cannot be rendered, with the file, the place in it, and what to do.
#[derive(Debug, Clone)]
pub struct SceneError {
    pub file: PathBuf,
    /// 1-based line and column, when known.
    pub line_col: Option<(usize, usize)>,
    /// The path of the offending value, e.g. `triangles[12].v[1]`; empty for the whole file.
    pub path: String,
    pub message: String,
    /// What the user can do about it.
    pub help: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some((l, c)) = self.line_col {
            write!(f, ":{l}:{c}")?;
        }
        write!(f, ": ")?;
        if !self.path.is_empty() {
            write!(f, "{}: ", self.path)?;
        }
        write!(f, "{}", self.message)?;
        if !self.help.is_empty() {
            write!(f, "\n  help: {}", self.help)?;
        }
        Ok(())
    }
}

impl std::error::Error for SceneError {}

impl Scene {
    /// Reads, parses and validates a scene file. Nothing is rendered or written here, so a bad
    /// scene is reported before any output exists.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let error = |message: String, help: &str| SceneError {
            file: path.to_path_buf(),
            line_col: None,
            path: String::new(),
            message,
            help: help.into(),
        };
        let unreadable = |e: std::io::Error| {
            error(
                format!("cannot read the scene file: {e}"),
                "check the path; the default scene is scenes/tncg15_room.json",
            )
        };
        let Some(bytes) = read_bounded(path, MAX_SCENE_BYTES).map_err(unreadable)? else {
            return Err(error(
                format!(
                    "the scene file is larger than {} MiB",
                    MAX_SCENE_BYTES >> 20
                ),
                "a scene file holds a camera, materials and a few primitives; is this the \
                 right file?",
            ));
        };
        Self::from_json(Self::decode(&bytes, path)?, path)
    }

    /// The scene file's bytes as text, or an error located at the first byte that is not
    /// UTF-8.
    pub fn decode<'a>(bytes: &'a [u8], path: &Path) -> Result<&'a str, SceneError> {
        std::str::from_utf8(bytes).map_err(|e| {
            let before = &bytes[..e.valid_up_to()];
            let before = std::str::from_utf8(before).unwrap_or_default();
            let before = locate::strip_bom(before);
            SceneError {
                file: path.to_path_buf(),
                line_col: Some(locate::line_col(before, before.len())),
                path: String::new(),
                message: "the scene file is not valid UTF-8 here".into(),
                help: "save the file as UTF-8".into(),
            }
        })
    }

    /// Parses and validates scene JSON and reads its meshes; `path` is used in messages and
    /// metadata, and mesh files are found relative to its folder.
    pub fn from_json(text: &str, path: &Path) -> Result<Scene, SceneError> {
        let desc = Self::parse(text, path)?;
        let body = locate::strip_bom(text);
        let mut sha1 = sha1_smol::Sha1::from(text.as_bytes());
        let folder = path.parent().unwrap_or(Path::new(""));
        let mut meshes = Vec::with_capacity(desc.meshes.len());
        for (i, m) in desc.meshes.iter().enumerate() {
            let at = JsonPath::root().key("meshes").index(i).key("file");
            let located = |message: String, help: String| SceneError {
                file: path.to_path_buf(),
                line_col: locate::locate(body, &at),
                path: at.to_string(),
                message,
                help,
            };
            let mesh_path = folder.join(&m.file);
            let bytes = read_bounded(&mesh_path, MAX_MESH_BYTES)
                .map_err(|e| {
                    located(
                        format!("cannot read the mesh file {}: {e}", mesh_path.display()),
                        "the path is relative to the scene file's folder; check it".into(),
                    )
                })?
                .ok_or_else(|| {
                    located(
                        format!(
                            "the mesh file {} is larger than {} MiB",
                            mesh_path.display(),
                            MAX_MESH_BYTES >> 20
                        ),
                        "simplify the mesh (hexray info shows what a mesh costs), or split it \
                         into several files"
                            .into(),
                    )
                })?;
            sha1.update(&bytes);
            let loaded = mesh::parse(&m.file, &bytes)
                .and_then(|data| {
                    drop(bytes);
                    mesh::place(m, mesh_path.clone(), &data, &m.transform())
                })
                .map_err(|e| located(format!("{}: {}", m.file, e.message), e.help))?;
            meshes.push(loaded);
        }
        Ok(Scene {
            desc,
            path: path.to_path_buf(),
            sha1: sha1.digest().to_string(),
            meshes,
        })
    }

    /// Parses and validates scene JSON without reading its meshes; `path` is only used in
    /// messages. Every error has a 1-based line and column (in characters) and, below the root,
    /// the JSON path of the value. A leading UTF-8 byte order mark is skipped, as most JSON
    /// readers do (positions are then those an editor shows).
    pub fn parse(text: &str, path: &Path) -> Result<SceneDesc, SceneError> {
        let text = locate::strip_bom(text);
        let located =
            |pos: usize, json_path: &JsonPath, message: String, help: String| SceneError {
                file: path.to_path_buf(),
                line_col: Some(locate::line_col(text, pos)),
                path: json_path.to_string(),
                message,
                help,
            };
        // serde keeps the last of two equal map keys (two materials of one name) without a word,
        // so duplicate keys are looked for first, anywhere in the document.
        if let Some(d) = locate::duplicate_key(text) {
            let (l, c) = locate::line_col(text, d.first_at);
            let under_materials =
                d.path.0.len() == 2 && d.path.0[0] == locate::Seg::Key("materials".into());
            let (what, help) = if under_materials {
                (
                    "duplicate material name",
                    "give each material its own name; geometry refers to materials by name",
                )
            } else {
                (
                    "duplicate key",
                    "each key may appear once in an object; remove one of the two",
                )
            };
            let key = match d.path.0.last() {
                Some(locate::Seg::Key(k)) => k.clone(),
                _ => String::new(),
            };
            return Err(located(
                d.at,
                &d.path,
                format!("{what} `{key}` (the first is at {l}:{c})"),
                help.into(),
            ));
        }
        let de = &mut serde_json::Deserializer::from_str(text);
        let parsed = match serde_path_to_error::deserialize::<_, SceneDesc>(&mut *de) {
            // Trailing content after the scene object is an error, not ignored.
            Ok(desc) => de.end().map(|()| desc).map_err(|e| (JsonPath::root(), e)),
            Err(e) => {
                let mut json_path = JsonPath::root();
                for seg in e.path().iter() {
                    json_path = match seg {
                        serde_path_to_error::Segment::Seq { index } => json_path.index(*index),
                        serde_path_to_error::Segment::Map { key } => json_path.key(key),
                        serde_path_to_error::Segment::Enum { variant } => json_path.key(variant),
                        serde_path_to_error::Segment::Unknown => json_path,
                    };
                }
                Err((json_path, e.into_inner()))
            }
        };
        let desc = parsed.map_err(|(mut json_path, inner)| {
            let mut pos = locate::offset_of(text, inner.line(), inner.column());
            let msg = inner.to_string();
            // serde_json appends " at line L column C"; the location is already in front.
            let mut msg = msg
                .rsplit_once(" at line ")
                .map_or(msg.as_str(), |(m, _)| m)
                .to_string();
            if inner.is_data() {
                // A value that parsed but has the wrong type or content: serde_json stands at
                // its end (for a material, at the closing brace); point at its start.
                if let Some(p) = locate::find_offset(text, &json_path) {
                    pos = p;
                }
                // An unknown field is reported on its object; point at the field itself.
                if let Some(field) = msg
                    .strip_prefix("unknown field `")
                    .and_then(|m| m.split('`').next())
                {
                    let with_field = json_path.key(field);
                    if let Some(p) = locate::find_offset(text, &with_field) {
                        json_path = with_field;
                        pos = p;
                    }
                }
                if msg.starts_with("invalid type: sequence, expected struct") {
                    msg = "expected an object with named fields, found an array".into();
                } else if let Some((head, _)) = msg.split_once(", expected struct ") {
                    // The Rust type's name means nothing to the scene's author.
                    msg = format!("{head}, expected an object");
                }
            }
            if msg.starts_with("trailing characters") {
                msg = "content after the end of the scene's JSON object".into();
            }
            let help = parse_help(&msg);
            located(pos, &json_path, msg, help)
        })?;
        validate::validate(&desc).map_err(|issue| SceneError {
            file: path.to_path_buf(),
            line_col: locate::locate_nearest(text, &issue.path),
            path: issue.path.to_string(),
            message: issue.message,
            help: issue.help,
        })?;
        Ok(desc)
    }

    /// The number of triangles the scene renders: inline, from meshes and from boxes.
    pub fn triangle_count(&self) -> usize {
        self.desc.triangles.len()
            + self.meshes.iter().map(|m| m.triangles.len()).sum::<usize>()
            + 12 * self.desc.boxes.len()
    }
}

impl Scene {
    /// A validation issue found after loading (e.g. one that depends on the method), located
    /// in the scene file as the loader's own.
    pub fn error_at(&self, issue: validate::Issue) -> SceneError {
        let text = std::fs::read_to_string(&self.path).unwrap_or_default();
        SceneError {
            file: self.path.clone(),
            line_col: locate::locate_nearest(&text, &issue.path),
            path: issue.path.to_string(),
            message: issue.message,
            help: issue.help,
        }
    }
}

fn parse_help(msg: &str) -> String {
    if msg.starts_with("unknown field") {
        "remove the field or fix its spelling; the fields this object takes are listed above".into()
    } else if msg.starts_with("unknown variant") {
        "material `type` must be one of diffuse, mirror, glass, emitter".into()
    } else if msg.starts_with("missing field") {
        "add the field; the scene format is documented in src/scene/format.rs".into()
    } else if msg.contains("untagged enum Scale") {
        "a mesh's scale is a number or [x, y, z]".into()
    } else if msg.starts_with("expected an object with named fields") {
        "write this as a JSON object, {\"field\": value, ...}; the positional array form of \
         an object is not accepted"
            .into()
    } else if msg.starts_with("content after the end") {
        "a scene file holds one JSON object; remove what follows its closing brace".into()
    } else if msg.contains("invalid type") || msg.contains("invalid length") {
        "numbers are JSON numbers and points are [x, y, z]".into()
    } else {
        "fix the JSON syntax at this place".into()
    }
}
