//! The light-transport methods a render can use.

use clap::ValueEnum;

/// Which estimator renders the image (`--method`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Method {
    /// Path tracing with next-event estimation and MIS (`src/cpu/path.rs`): one independent
    /// camera path per sample.
    Path,
    /// Light tracing (`src/cpu/light_path.rs`): light subpaths connected to the camera. Sees
    /// nothing through mirrors or glass: surfaces seen only that way stay black.
    Light,
    /// Bidirectional path tracing (`src/cpu/bdpt.rs`): every connection of a camera subpath and
    /// a light subpath, weighed by MIS.
    Bdpt,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Path => "path",
            Method::Light => "light",
            Method::Bdpt => "bdpt",
        }
    }

    /// The method called `name` (as in the EXR metadata).
    pub fn from_name(name: &str) -> Option<Method> {
        Method::value_variants()
            .iter()
            .copied()
            .find(|m| m.name() == name)
    }

    /// Whether the method splats light subpaths into the image, so that an iteration's pixels
    /// share samples and its statistics are batch means (`film.rs`).
    pub fn splats(self) -> bool {
        matches!(self, Method::Light | Method::Bdpt)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
