//! The GPU's light tracing and BDPT compute the CPU's images: `tests/gpu_parity.rs`'s statistic
//! (per 8x8 block and channel, Welch's t-test with a Bonferroni correction at α = 0.01 overall,
//! and each channel's image-mean ratio within 4 s.e. of 1), between a CPU and a GPU render of
//! other seeds, 64x64 pixels. A light subpath splats into several pixels (light tracing's
//! connections to the camera), so the pixels of an iteration are not independent: as for the
//! merging methods, each standard error comes from the scatter of the iterations' block means
//! (`parity_of_iterations`, which counts that covariance). Power: a GPU whose mirrors and glass
//! pass 10 % less light is rejected on tncg15_room.

use crate::common::parity::{gpu_against_cpu_iterations, Parity};
use crate::common::*;
use hexray::transport::faults::Faults;
use hexray::transport::merging::MergeRadius;
use hexray::transport::method::Method;

const SIZE: u32 = 64;

fn cpu_against_gpu(
    rel: &str,
    method: Method,
    iterations: u32,
    gpu_faults: Faults,
) -> Option<Parity> {
    // Light tracing and BDPT do not merge: the radius is not used.
    let (scene, flat) = load(rel);
    let camera = hexray::transport::camera::Camera::new(&scene.desc.camera, SIZE, SIZE);
    let radius = MergeRadius::default_for(&flat, &camera, method);
    gpu_against_cpu_iterations(rel, SIZE, iterations, method, radius, gpu_faults)
}

fn assert_same(rel: &str, method: Method, iterations: u32) {
    if let Some(p) = cpu_against_gpu(rel, method, iterations, Faults::NONE) {
        assert!(p.same(), "{method} {rel}: {p}");
    }
}

#[test]
fn gpu_light_tracing_matches_cpu_on_cornell_box() {
    assert_same("scenes/cornell_box.json", Method::Light, 64);
}

#[test]
fn gpu_light_tracing_matches_cpu_on_tncg15_room() {
    assert_same("scenes/tncg15_room.json", Method::Light, 64);
}

#[test]
fn gpu_bdpt_matches_cpu_on_cornell_box() {
    assert_same("scenes/cornell_box.json", Method::Bdpt, 64);
}

#[test]
fn gpu_bdpt_matches_cpu_on_tncg15_room() {
    assert_same("scenes/tncg15_room.json", Method::Bdpt, 64);
}

#[test]
fn gpu_bdpt_matches_cpu_on_glass_room() {
    assert_same("scenes/glass_room.json", Method::Bdpt, 64);
}

#[test]
fn bidirectional_parity_rejects_gpu_mirrors_10_percent_too_dark() {
    let dim = Faults {
        specular_scale: 0.9,
        ..Faults::NONE
    };
    let Some(p) = cpu_against_gpu("scenes/tncg15_room.json", Method::Bdpt, 64, dim) else {
        return;
    };
    assert!(!p.same(), "dim GPU mirrors went unnoticed: {p}");
}
