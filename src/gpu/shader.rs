//! The WGSL sources: one file per module of `src/`, concatenated in dependency order into the
//! single module that wgpu compiles (WGSL has no includes), and validated by naga.

/// Where the scene arrays live on the device (bindings 0 to 5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Residency {
    /// Read-only storage buffers: any scene size.
    Storage,
    /// Uniform buffers of fixed length: only where every array fits the uniform binding limit;
    /// faster on lavapipe (Mesa 22.3; tncg15_room 1.7x), whose storage loads go one lane at a
    /// time.
    Uniform,
}

pub const SCENE: (&str, &str) = ("scene.wgsl", include_str!("../../shaders/scene.wgsl"));
pub const BINDINGS_STORAGE: (&str, &str) = (
    "bindings_storage.wgsl",
    include_str!("../../shaders/bindings_storage.wgsl"),
);
pub const BINDINGS_UNIFORM: (&str, &str) = (
    "bindings_uniform.wgsl",
    include_str!("../../shaders/bindings_uniform.wgsl"),
);
/// The files after the bindings, in dependency order.
pub const BODY: [(&str, &str); 19] = [
    ("sampling.wgsl", include_str!("../../shaders/sampling.wgsl")),
    ("geometry.wgsl", include_str!("../../shaders/geometry.wgsl")),
    ("bvh.wgsl", include_str!("../../shaders/bvh.wgsl")),
    (
        "clearance.wgsl",
        include_str!("../../shaders/clearance.wgsl"),
    ),
    ("merging.wgsl", include_str!("../../shaders/merging.wgsl")),
    ("bsdf.wgsl", include_str!("../../shaders/bsdf.wgsl")),
    ("light.wgsl", include_str!("../../shaders/light.wgsl")),
    (
        "planar_mirror.wgsl",
        include_str!("../../shaders/planar_mirror.wgsl"),
    ),
    ("camera.wgsl", include_str!("../../shaders/camera.wgsl")),
    ("film.wgsl", include_str!("../../shaders/film.wgsl")),
    ("splat.wgsl", include_str!("../../shaders/splat.wgsl")),
    ("subpath.wgsl", include_str!("../../shaders/subpath.wgsl")),
    ("path.wgsl", include_str!("../../shaders/path.wgsl")),
    ("whitted.wgsl", include_str!("../../shaders/whitted.wgsl")),
    (
        "radiosity.wgsl",
        include_str!("../../shaders/radiosity.wgsl"),
    ),
    (
        "light_path.wgsl",
        include_str!("../../shaders/light_path.wgsl"),
    ),
    (
        "hash_grid.wgsl",
        include_str!("../../shaders/hash_grid.wgsl"),
    ),
    ("bdpt.wgsl", include_str!("../../shaders/bdpt.wgsl")),
    (
        "photon_map.wgsl",
        include_str!("../../shaders/photon_map.wgsl"),
    ),
];

/// Every shader file (for tests that check none is left out).
pub fn all_files() -> Vec<&'static str> {
    let mut v = vec![SCENE.0, BINDINGS_STORAGE.0, BINDINGS_UNIFORM.0];
    v.extend(BODY.iter().map(|(n, _)| *n));
    v
}

/// What the kernel is specialised to: the lengths of the scene arrays (the uniform bindings'
/// `LEN_*` constants) and the traversal stack's size (`STACK_SIZE` in bvh.wgsl: the traversal
/// pushes at most three nodes per level, and lavapipe keeps a private stack sized to the scene
/// in registers where a fixed 64-entry one spilled to memory; docs/design/gpu.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ArrayLengths {
    pub triangles: usize,
    pub spheres: usize,
    pub materials: usize,
    pub emitters: usize,
    pub nodes: usize,
    /// In vec4<u32>s (four primitive references each).
    pub prims: usize,
    /// A bound on the traversal stack (`bvh::stack_size`: three entries per level).
    pub stack_size: usize,
}

/// Replaces the value of every `const NAME: u32 = ...;` line whose NAME is in `values`.
fn specialise(text: &str, values: &[(&str, usize)]) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let name = line
            .strip_prefix("const ")
            .and_then(|l| l.split(':').next())
            .unwrap_or("");
        match values.iter().find(|(n, _)| *n == name) {
            Some((n, v)) => out.push_str(&format!("const {n}: u32 = {}u;", (*v).max(1))),
            None => out.push_str(line),
        }
        out.push('\n');
    }
    out
}

/// The whole renderer as one WGSL module. Each file starts with a comment naming it, so naga's
/// error positions can be traced back.
pub fn source(residency: Residency, lengths: ArrayLengths) -> String {
    let values = [
        ("LEN_TRIANGLES", lengths.triangles),
        ("LEN_SPHERES", lengths.spheres),
        ("LEN_MATERIALS", lengths.materials),
        ("LEN_EMITTERS", lengths.emitters),
        ("LEN_NODES", lengths.nodes),
        ("LEN_PRIMS", lengths.prims),
        ("STACK_SIZE", lengths.stack_size),
    ];
    let bindings = match residency {
        Residency::Storage => BINDINGS_STORAGE,
        Residency::Uniform => BINDINGS_UNIFORM,
    };
    let mut s = String::new();
    for (name, text) in [SCENE, bindings].iter().chain(BODY.iter()) {
        s.push_str(&format!("// ---- shaders/{name} ----\n"));
        s.push_str(&specialise(text, &values));
        s.push('\n');
    }
    s
}

/// Parses and validates WGSL with naga (the same front end wgpu uses), returning the module and
/// its layout information, or naga's message with the source location.
pub fn validate(source: &str) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| e.emit_to_string(source))?;
    Ok((module, info))
}
