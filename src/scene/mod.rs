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
        // Read at most one byte past the limit, so that /dev/zero or a huge file is refused
        // without reading it all.
        use std::io::Read;
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .map_err(unreadable)?
            .take(MAX_SCENE_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(unreadable)?;
        if bytes.len() as u64 > MAX_SCENE_BYTES {
            return Err(error(
                format!(
                    "the scene file is larger than {} MiB",
                    MAX_SCENE_BYTES >> 20
                ),
                "a scene file holds a camera, materials and a few primitives; is this the \
                 right file?",
            ));
        }
        let text = String::from_utf8(bytes).map_err(|e| {
            let before = &e.as_bytes()[..e.utf8_error().valid_up_to()];
            let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
            let column = before.len()
                - before
                    .iter()
                    .rposition(|&b| b == b'\n')
                    .map_or(0, |i| i + 1)
                + 1;
            SceneError {
                line_col: Some((line, column)),
                ..error(
                    "the scene file is not valid UTF-8 here".into(),
                    "save the file as UTF-8",
                )
            }
        })?;
        Self::from_json(&text, path)
    }

    /// Parses and validates scene JSON; `path` is only used in messages and metadata.
    pub fn from_json(text: &str, path: &Path) -> Result<Scene, SceneError> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let desc: SceneDesc = serde_path_to_error::deserialize(de).map_err(|e| {
            let inner = e.inner();
            let mut line_col = (inner.line() > 0).then(|| (inner.line(), inner.column()));
            let mut json_path = JsonPath::root();
            for seg in e.path().iter() {
                json_path = match seg {
                    serde_path_to_error::Segment::Seq { index } => json_path.index(*index),
                    serde_path_to_error::Segment::Map { key } => json_path.key(key),
                    serde_path_to_error::Segment::Enum { variant } => json_path.key(variant),
                    serde_path_to_error::Segment::Unknown => json_path,
                };
            }
            let msg = inner.to_string();
            // serde_json appends " at line L column C"; the location is already in front.
            let msg = msg
                .rsplit_once(" at line ")
                .map_or(msg.as_str(), |(m, _)| m)
                .to_string();
            // Inside a material (an internally tagged enum) serde reports an unknown field at the
            // end of the object; point at the field itself.
            if let Some(field) = msg
                .strip_prefix("unknown field `")
                .and_then(|m| m.split('`').next())
            {
                let with_field = json_path.key(field);
                if json_path.0.last() != with_field.0.last() {
                    if let Some(lc) = locate::locate(text, &with_field) {
                        json_path = with_field;
                        line_col = Some(lc);
                    }
                }
            }
            SceneError {
                file: path.to_path_buf(),
                line_col,
                path: json_path.to_string(),
                help: parse_help(&msg),
                message: msg,
            }
        })?;
        validate::validate(&desc).map_err(|issue| SceneError {
            file: path.to_path_buf(),
            line_col: locate::locate(text, &issue.path),
            path: issue.path.to_string(),
            message: issue.message,
            help: issue.help,
        })?;
        let mut sha1 = sha1_smol::Sha1::from(text.as_bytes());
        let folder = path.parent().unwrap_or(Path::new(""));
        let mut meshes = Vec::with_capacity(desc.meshes.len());
        for (i, m) in desc.meshes.iter().enumerate() {
            let at = JsonPath::root().key("meshes").index(i).key("file");
            let located = |message: String, help: String| SceneError {
                file: path.to_path_buf(),
                line_col: locate::locate(text, &at),
                path: at.to_string(),
                message,
                help,
            };
            let mesh_path = folder.join(&m.file);
            let bytes = std::fs::read(&mesh_path).map_err(|e| {
                located(
                    format!("cannot read the mesh file {}: {e}", mesh_path.display()),
                    "the path is relative to the scene file's folder; check it".into(),
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
            line_col: locate::locate(&text, &issue.path),
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
    } else if msg.contains("invalid type") || msg.contains("invalid length") {
        "numbers are JSON numbers and points are [x, y, z]".into()
    } else {
        "fix the JSON syntax at this place".into()
    }
}
