//! The WGSL sources: one file per module of `src/`, concatenated in dependency order into the
//! single module that wgpu compiles (WGSL has no includes), and validated by naga.

/// Where the scene arrays live on the device (bindings 0 to 5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Residency {
    /// Read-only storage buffers: any scene size.
    Storage,
    /// Uniform buffers of fixed length: only where every array fits the uniform binding limit;
    /// about 10x faster on lavapipe (Mesa 22.3), whose storage loads go one lane at a time.
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
pub const BODY: [(&str, &str); 6] = [
    ("sampling.wgsl", include_str!("../../shaders/sampling.wgsl")),
    ("geometry.wgsl", include_str!("../../shaders/geometry.wgsl")),
    ("bvh.wgsl", include_str!("../../shaders/bvh.wgsl")),
    ("bsdf.wgsl", include_str!("../../shaders/bsdf.wgsl")),
    ("light.wgsl", include_str!("../../shaders/light.wgsl")),
    ("path.wgsl", include_str!("../../shaders/path.wgsl")),
];

/// Every shader file (for tests that check none is left out).
pub fn all_files() -> Vec<&'static str> {
    let mut v = vec![SCENE.0, BINDINGS_STORAGE.0, BINDINGS_UNIFORM.0];
    v.extend(BODY.iter().map(|(n, _)| *n));
    v
}

/// Lengths of the scene arrays, written into the uniform bindings' `LEN_*` constants.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ArrayLengths {
    pub triangles: usize,
    pub spheres: usize,
    pub materials: usize,
    pub emitters: usize,
    pub nodes: usize,
    /// In vec4<u32>s (four primitive references each).
    pub prims: usize,
}

/// The whole renderer as one WGSL module. Each file starts with a comment naming it, so naga's
/// error positions can be traced back.
pub fn source(residency: Residency, lengths: ArrayLengths) -> String {
    let bindings = match residency {
        Residency::Storage => BINDINGS_STORAGE.1.to_string(),
        Residency::Uniform => {
            let mut text = String::new();
            for line in BINDINGS_UNIFORM.1.lines() {
                let set = |name: &str, n: usize| format!("const LEN_{name}: u32 = {}u;", n.max(1));
                let line = match line.split(':').next().unwrap_or("") {
                    "const LEN_TRIANGLES" => set("TRIANGLES", lengths.triangles),
                    "const LEN_SPHERES" => set("SPHERES", lengths.spheres),
                    "const LEN_MATERIALS" => set("MATERIALS", lengths.materials),
                    "const LEN_EMITTERS" => set("EMITTERS", lengths.emitters),
                    "const LEN_NODES" => set("NODES", lengths.nodes),
                    "const LEN_PRIMS" => set("PRIMS", lengths.prims),
                    _ => line.to_string(),
                };
                text.push_str(&line);
                text.push('\n');
            }
            text
        }
    };
    let name = match residency {
        Residency::Storage => BINDINGS_STORAGE.0,
        Residency::Uniform => BINDINGS_UNIFORM.0,
    };
    let mut s = String::new();
    let mut push = |name: &str, text: &str| {
        s.push_str(&format!("// ---- shaders/{name} ----\n"));
        s.push_str(text);
        s.push('\n');
    };
    push(SCENE.0, SCENE.1);
    push(name, &bindings);
    for (n, t) in BODY {
        push(n, t);
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
