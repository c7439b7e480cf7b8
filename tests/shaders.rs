//! The WGSL is code: every file in `shaders/` is part of the kernel, and naga (the front end
//! wgpu uses) parses and validates it, here with no GPU.

use hexray::gpu::shader::{all_files, source, validate, ArrayLengths, Residency};

#[test]
fn every_wgsl_file_is_in_the_kernel() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut on_disk: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".wgsl"))
        .collect();
    on_disk.sort();
    let mut used: Vec<String> = all_files().iter().map(|n| n.to_string()).collect();
    used.sort();
    assert_eq!(on_disk, used);
}

#[test]
fn the_kernel_parses_and_validates_with_naga_in_both_residencies() {
    let lengths = ArrayLengths {
        triangles: 26,
        spheres: 1,
        materials: 9,
        emitters: 2,
        nodes: 7,
        prims: 7,
        stack_size: 9,
    };
    for residency in [Residency::Storage, Residency::Uniform] {
        let src = source(residency, lengths);
        if let Err(e) = validate(&src) {
            panic!("{residency:?}: {e}");
        }
    }
}
