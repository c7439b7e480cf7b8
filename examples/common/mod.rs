//! What the examples share: their scene arguments and loading them.

use hexray::scene::Scene;

/// The scene files named on the command line, or the three reference scenes.
pub fn scene_paths(args: Vec<String>) -> Vec<String> {
    if !args.is_empty() {
        return args;
    }
    ["tncg15_room", "cornell_box", "glass_room"]
        .iter()
        .map(|s| format!("{}/scenes/{s}.json", env!("CARGO_MANIFEST_DIR")))
        .collect()
}

/// The scene at `path`, or its located error and exit status 2.
pub fn load(path: &str) -> Scene {
    Scene::load(std::path::Path::new(path)).unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2);
    })
}

/// The scene file's name without its extension, for a table's first column.
pub fn name(path: &str) -> String {
    std::path::Path::new(path)
        .file_stem()
        .map_or(path.to_string(), |s| s.to_string_lossy().into_owned())
}
