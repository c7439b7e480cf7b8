//! Helpers shared by the integration tests: load a scene, render it on the CPU, and state
//! statistical expectations.
#![allow(dead_code)]

pub mod parity;

use hexray::camera::Camera;
use hexray::cpu::{render_pass, Faults};
use hexray::film::Film;
use hexray::flat::FlatScene;
use hexray::scene::Scene;
use std::path::{Path, PathBuf};

/// A path under the repository root.
pub fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

pub fn load(rel: &str) -> (Scene, FlatScene) {
    let scene = Scene::load(&repo(rel)).unwrap_or_else(|e| panic!("{e}"));
    let flat = FlatScene::build(&scene);
    (scene, flat)
}

/// Renders `spp` samples per pixel of a scene file on the CPU backend (all cores).
pub fn render_cpu(rel: &str, width: u32, height: u32, spp: u32, seed: u32, faults: Faults) -> Film {
    render_cpu_light_samples(rel, width, height, spp, seed, 1, faults)
}

/// [`render_cpu`] with `light_samples` shadow rays per diffuse vertex.
pub fn render_cpu_light_samples(
    rel: &str,
    width: u32,
    height: u32,
    spp: u32,
    seed: u32,
    light_samples: u32,
    faults: Faults,
) -> Film {
    let (scene, flat) = load(rel);
    let camera = Camera::new(&scene.desc.camera, width, height);
    let mut film = Film::new(width, height);
    render_pass(
        &flat,
        &camera,
        seed,
        0,
        spp,
        light_samples,
        faults,
        &mut film,
    );
    film
}

/// z-score of each channel of the image mean against an exact value: (mean − truth) / s.e.
pub fn image_mean_z(film: &Film, truth: [f64; 3]) -> ([f64; 3], [f64; 3], [f64; 3]) {
    let (mean, se) = film.image_mean();
    let z = [0, 1, 2].map(|c| (mean[c] - truth[c]) / se[c]);
    (mean, se, z)
}

/// Asserts that the image mean equals `truth` within 4 standard errors in every channel. For a
/// correct renderer |z| > 4 has probability 6e-5 per channel (normal tails; the image mean of
/// thousands of independent pixel estimates is normal to a good approximation).
pub fn assert_mean_within_4_se(film: &Film, truth: [f64; 3], what: &str) {
    let (mean, se, z) = image_mean_z(film, truth);
    for c in 0..3 {
        assert!(
            z[c].abs() <= 4.0,
            "{what}: channel {c} mean {:.6} vs exact {:.6}: z = {:.2} (s.e. {:.2e})",
            mean[c],
            truth[c],
            z[c],
            se[c]
        );
    }
    eprintln!(
        "{what}: mean {:.5} {:.5} {:.5}, exact {:.5} {:.5} {:.5}, z {:.2} {:.2} {:.2}",
        mean[0], mean[1], mean[2], truth[0], truth[1], truth[2], z[0], z[1], z[2]
    );
}

/// The GPU for tests, shared by all tests of a binary: None (with the reason printed) when no
/// adapter exists, unless `CI` is set, where a missing adapter is a failure (CI installs
/// lavapipe, so GPU tests must run there).
pub fn gpu() -> Option<&'static hexray::gpu::Gpu> {
    use std::sync::OnceLock;
    static GPU: OnceLock<Result<hexray::gpu::Gpu, String>> = OnceLock::new();
    match GPU.get_or_init(|| hexray::gpu::acquire(None).map_err(|e| e.to_string())) {
        Ok(g) => Some(g),
        Err(e) if std::env::var_os("CI").is_some() => panic!("CI is set but {e}"),
        Err(e) => {
            eprintln!("skipping GPU test: {e}");
            None
        }
    }
}

/// Renders `spp` samples per pixel of a scene file on the GPU backend (no runtime checks, as
/// the CLI does).
pub fn render_gpu(
    gpu: &hexray::gpu::Gpu,
    rel: &str,
    width: u32,
    height: u32,
    spp: u32,
    seed: u32,
    faults: Faults,
) -> Film {
    render_gpu_light_samples(gpu, rel, width, height, spp, seed, 1, faults)
}

/// [`render_gpu`] with `light_samples` shadow rays per diffuse vertex.
#[allow(clippy::too_many_arguments)]
pub fn render_gpu_light_samples(
    gpu: &hexray::gpu::Gpu,
    rel: &str,
    width: u32,
    height: u32,
    spp: u32,
    seed: u32,
    light_samples: u32,
    faults: Faults,
) -> Film {
    let (scene, flat) = load(rel);
    let camera = Camera::new(&scene.desc.camera, width, height);
    let mut r = hexray::gpu::GpuRenderer::new(
        &gpu.device,
        &gpu.queue,
        &flat,
        camera,
        seed,
        faults,
        hexray::gpu::Checks::Unchecked,
        hexray::gpu::Residency::preferred(&gpu.info, &gpu.device.limits(), &flat),
    )
    .unwrap();
    r.set_light_samples(light_samples);
    let mut film = Film::new(width, height);
    r.render(0, spp, &mut film).unwrap();
    film
}
