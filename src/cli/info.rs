//! `hexray info`: the GPU adapters, or a scene's size, BVH and memory without rendering.

use super::*;
use clap::Args;
use hexray::gpu;
use hexray::layout::FlatScene;
use hexray::render::CpuBackend;
use hexray::scene::Scene;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Args, Debug, Clone)]
pub(crate) struct InfoArgs {
    /// A scene file to describe (without it, the GPU adapters are listed).
    pub(crate) scene: Option<PathBuf>,
}

/// One line per mesh: what was read and what was dropped.
pub(crate) fn mesh_lines(scene: &Scene) -> Vec<String> {
    scene
        .meshes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let dropped = match m.first_dropped_face {
                Some(face) => format!(
                    "; dropped {} triangles of zero area in f32 (the first from face {face})",
                    m.dropped
                ),
                None => String::new(),
            };
            format!(
                "meshes[{i}] {}: {} vertices, {} faces, {} triangles{dropped}",
                m.file,
                m.vertices,
                m.faces,
                m.triangles.len()
            )
        })
        .collect()
}

/// `hexray info SCENE`: loads and flattens the scene (exit 2 if it is bad) and prints its size,
/// bounds, BVH and memory, without rendering.
pub(crate) fn scene_info(path: &Path) -> ExitCode {
    use std::io::Write;
    let started = std::time::Instant::now();
    let scene = match super::render::load_scene(path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let loaded = started.elapsed().as_secs_f64();
    // The scene as each backend flattens it: their BVHs differ in large scenes.
    let flat = FlatScene::build(&scene, CpuBackend::TRAVERSAL);
    let gpu_flat = FlatScene::build(&scene, gpu::GpuRenderer::TRAVERSAL);
    let mut out = std::io::stdout().lock();
    let mib = |b: usize| b as f64 / (1u64 << 20) as f64;
    let (lo, hi) = flat.bounds();
    let cpu = [
        ("triangles", std::mem::size_of_val(&flat.triangles[..])),
        ("packs", std::mem::size_of_val(&flat.packs[..])),
        ("nodes", std::mem::size_of_val(&flat.nodes[..])),
        ("wide nodes", std::mem::size_of_val(&flat.wide[..])),
        ("prims", std::mem::size_of_val(&flat.prims[..])),
        (
            "other",
            std::mem::size_of_val(&flat.spheres[..])
                + std::mem::size_of_val(&flat.materials[..])
                + std::mem::size_of_val(&flat.emitters[..]),
        ),
    ];
    let gpu_arrays = gpu::limits::scene_arrays(&gpu_flat);
    let list = |arrays: &[(&str, usize)]| {
        arrays
            .iter()
            .map(|(n, b)| format!("{n} {:.2}", mib(*b)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let (largest, largest_bytes) = gpu_arrays.iter().max_by_key(|a| a.1).copied().unwrap();
    let _ = writeln!(out, "scene: {} ({})", path.display(), scene.desc.name);
    let _ = writeln!(out, "scene_sha1: {}", scene.sha1);
    let _ = writeln!(
        out,
        "triangles: {} ({} inline, {} from meshes, {} from boxes)",
        flat.triangles.len(),
        scene.desc.triangles.len(),
        scene
            .meshes
            .iter()
            .map(|m| m.triangles.len())
            .sum::<usize>(),
        12 * scene.desc.boxes.len()
    );
    for line in mesh_lines(&scene) {
        let _ = writeln!(out, "  {line}");
    }
    let _ = writeln!(
        out,
        "spheres: {}, materials: {}, emitters: {}",
        flat.spheres.len(),
        flat.materials.len(),
        flat.emitters.len()
    );
    let _ = writeln!(
        out,
        "bounds: min [{}, {}, {}], max [{}, {}, {}]",
        lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
    );
    let _ = writeln!(
        out,
        "bvh cpu: {} four-wide nodes ({} eight-wide), depth {}, {} prims entries, built in {:.3} s",
        flat.nodes.len(),
        flat.wide.len(),
        hexray::accel::bvh::depth(&flat.nodes),
        flat.prims.len(),
        flat.bvh_seconds
    );
    let _ = writeln!(
        out,
        "bvh gpu: {} four-wide nodes, depth {}, {} prims entries, built in {:.3} s",
        gpu_flat.nodes.len(),
        hexray::accel::bvh::depth(&gpu_flat.nodes),
        gpu_flat.prims.len(),
        gpu_flat.bvh_seconds
    );
    let _ = writeln!(
        out,
        "memory cpu: {:.2} MiB ({})",
        mib(cpu.iter().map(|a| a.1).sum()),
        list(&cpu)
    );
    let _ = writeln!(
        out,
        "memory gpu: {:.2} MiB ({}); largest binding {largest} {:.2} MiB",
        mib(gpu_arrays.iter().map(|a| a.1).sum()),
        list(&gpu_arrays),
        mib(largest_bytes)
    );
    let _ = writeln!(out, "load_seconds: {loaded:.3}");
    ExitCode::SUCCESS
}

/// Lists the adapters. Written with `writeln!` and its errors ignored, so that a reader that
/// stops early (`hexray info | grep -q ...`) ends the listing instead of a panic.
pub(crate) fn info() -> ExitCode {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let list = gpu::context::adapters();
    if list.is_empty() {
        let _ = writeln!(
            out,
            "no GPU adapters found; for software Vulkan: {}",
            gpu::context::LAVAPIPE_HINT
        );
        return ExitCode::SUCCESS;
    }
    for (i, a) in list.iter().enumerate() {
        let info = a.get_info();
        let l = a.limits();
        let _ = writeln!(out, "[{i}] {}", gpu::context::describe(&info));
        let _ = writeln!(
            out,
            "    max storage buffers/stage {}, max storage binding {} MiB, max workgroup invocations {}, max workgroups/dim {}",
            l.max_storage_buffers_per_shader_stage,
            l.max_storage_buffer_binding_size >> 20,
            l.max_compute_invocations_per_workgroup,
            l.max_compute_workgroups_per_dimension
        );
    }
    ExitCode::SUCCESS
}
