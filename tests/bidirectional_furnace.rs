//! The furnace tests of `tests/furnace.rs` for the bidirectional methods, on both backends: in a
//! closed enclosure whose walls emit 1 − ρ and reflect ρ, the radiance is exactly 1 everywhere,
//! whichever strategies sample it and however the MIS weights share it out. BDPT runs on every
//! furnace (ρ = 0.5, 0.8, 0.95, a mirror sphere and a glass sphere inside); light tracing on
//! the diffuse ones only, since it cannot see the spheres (nothing reaches the camera through a
//! specular bounce, and the mirror furnace shows it: light tracing's image there is too dark).
//!
//! Statistic: the image mean over 32x32 pixels against 1, |mean − 1| ≤ 4 s.e. per channel (the
//! s.e. from the batch means of the iterations), with the s.e. below 0.5 % so that a 2 % error
//! could not hide. Planted: a depth cap of 8 (BDPT, both backends) and a 3 % dim mirror.

use crate::common::*;
use hexray::film::Film;
use hexray::transport::faults::Faults;
use hexray::transport::method::Method;

const SIZE: u32 = 32;
/// Iterations: each gives every pixel one sample.
const ITERATIONS: u32 = 64;

fn check(what: &str, film: &Film) {
    let (_, se) = film.image_mean();
    assert!(
        se.iter().all(|&s| s < 0.005),
        "{what}: s.e. {se:?} too large to resolve 2 %"
    );
    assert_mean_within_4_se(film, [1.0; 3], what);
    assert_eq!(film.dropped(), 0, "{what}: non-finite samples");
}

fn on_cpu(rel: &str, method: Method) {
    let film = render_cpu_method(rel, SIZE, SIZE, ITERATIONS, 22, method, Faults::NONE);
    check(&format!("{method} {rel}"), &film);
}

fn on_gpu(rel: &str, method: Method) {
    let Some(g) = gpu() else { return };
    let film = render_gpu_method(g, rel, SIZE, SIZE, ITERATIONS, 23, method, Faults::NONE);
    check(&format!("GPU {method} {rel}"), &film);
}

const HALF: &str = "scenes/furnace/diffuse_0_5.json";
const BRIGHT: &str = "scenes/furnace/diffuse_0_8.json";
const WHITE: &str = "scenes/furnace/diffuse_0_95.json";
const MIRROR: &str = "scenes/furnace/mirror_sphere.json";
const GLASS: &str = "scenes/furnace/glass_sphere.json";

#[test]
fn bdpt_furnace_albedo_0_5_converges_to_1() {
    on_cpu(HALF, Method::Bdpt);
}

#[test]
fn bdpt_furnace_albedo_0_8_converges_to_1() {
    on_cpu(BRIGHT, Method::Bdpt);
}

#[test]
fn bdpt_furnace_albedo_0_95_converges_to_1() {
    on_cpu(WHITE, Method::Bdpt);
}

#[test]
fn bdpt_mirror_sphere_in_a_furnace_converges_to_1() {
    on_cpu(MIRROR, Method::Bdpt);
}

#[test]
fn bdpt_glass_sphere_in_a_furnace_converges_to_1() {
    on_cpu(GLASS, Method::Bdpt);
}

#[test]
fn light_tracing_furnace_albedo_0_5_converges_to_1() {
    on_cpu(HALF, Method::Light);
}

#[test]
fn light_tracing_furnace_albedo_0_95_converges_to_1() {
    on_cpu(WHITE, Method::Light);
}

#[test]
fn gpu_bdpt_furnace_albedo_0_5_converges_to_1() {
    on_gpu(HALF, Method::Bdpt);
}

#[test]
fn gpu_bdpt_furnace_albedo_0_95_converges_to_1() {
    on_gpu(WHITE, Method::Bdpt);
}

#[test]
fn gpu_bdpt_mirror_sphere_in_a_furnace_converges_to_1() {
    on_gpu(MIRROR, Method::Bdpt);
}

#[test]
fn gpu_bdpt_glass_sphere_in_a_furnace_converges_to_1() {
    on_gpu(GLASS, Method::Bdpt);
}

#[test]
fn gpu_light_tracing_furnace_albedo_0_8_converges_to_1() {
    on_gpu(BRIGHT, Method::Light);
}

/// Light tracing sees nothing through the mirror sphere: its furnace image is too dark, as
/// `--help` says, which is why it is tested only where it is unbiased.
#[test]
fn light_tracing_cannot_see_the_mirror_sphere() {
    let film = render_cpu_method(
        MIRROR,
        SIZE,
        SIZE,
        ITERATIONS,
        22,
        Method::Light,
        Faults::NONE,
    );
    let (_, _, z) = image_mean_z(&film, [1.0; 3]);
    assert!(z.iter().all(|z| *z < -4.0), "z = {z:?}");
}

fn assert_too_dark(what: &str, film: &Film) {
    let (_, _, z) = image_mean_z(film, [1.0; 3]);
    eprintln!("{what}: z {z:?}");
    assert!(
        z.iter().all(|z| *z < -4.0),
        "{what} went unnoticed: z = {z:?}"
    );
}

const DEPTH_CAP: Faults = Faults {
    max_bounces: 8,
    ..Faults::NONE
};

/// The test has power: BDPT with paths capped at 8 bounces loses much of the white furnace's
/// light (ρ^9 of it for each pixel's paths, 37 % at ρ = 0.95).
#[test]
fn bdpt_furnace_rejects_a_depth_cap() {
    let film = render_cpu_method(WHITE, SIZE, SIZE, ITERATIONS, 22, Method::Bdpt, DEPTH_CAP);
    assert_too_dark("BDPT with a depth cap", &film);
}

#[test]
fn gpu_bdpt_furnace_rejects_a_depth_cap() {
    let Some(g) = gpu() else { return };
    let film = render_gpu_method(
        g,
        WHITE,
        SIZE,
        SIZE,
        ITERATIONS,
        23,
        Method::Bdpt,
        DEPTH_CAP,
    );
    assert_too_dark("GPU BDPT with a depth cap", &film);
}

/// ... and a mirror that reflects 97 % of what it should, on every subpath that meets it.
#[test]
fn bdpt_furnace_rejects_a_dim_mirror() {
    let dim = Faults {
        specular_scale: 0.97,
        ..Faults::NONE
    };
    let film = render_cpu_method(MIRROR, SIZE, SIZE, 256, 22, Method::Bdpt, dim);
    assert_too_dark("BDPT with a dim mirror", &film);
}
