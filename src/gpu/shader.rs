//! The WGSL sources: one file per module of `src/`, concatenated in dependency order into the
//! single module that wgpu compiles (WGSL has no includes), and validated by naga.

/// The shader files, in the order they are concatenated.
pub const FILES: [(&str, &str); 7] = [
    ("scene.wgsl", include_str!("../../shaders/scene.wgsl")),
    ("sampling.wgsl", include_str!("../../shaders/sampling.wgsl")),
    ("geometry.wgsl", include_str!("../../shaders/geometry.wgsl")),
    ("bvh.wgsl", include_str!("../../shaders/bvh.wgsl")),
    ("bsdf.wgsl", include_str!("../../shaders/bsdf.wgsl")),
    ("light.wgsl", include_str!("../../shaders/light.wgsl")),
    ("path.wgsl", include_str!("../../shaders/path.wgsl")),
];

/// The whole renderer as one WGSL module; each file starts with a comment naming it, so naga's
/// error positions can be traced back.
pub fn source() -> String {
    let mut s = String::new();
    for (name, text) in FILES {
        s.push_str(&format!("// ---- shaders/{name} ----\n"));
        s.push_str(text);
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
