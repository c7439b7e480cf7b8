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

/// `ITERATIONS` iterations of `method` on `backend`: seed 22 on the CPU, 23 on the GPU.
fn render(backend: Backend, rel: &str, method: Method, faults: Faults) -> Film {
    let seed = match backend {
        Backend::Cpu => 22,
        Backend::Gpu => 23,
    };
    Render::file(rel)
        .size(SIZE, SIZE)
        .spp(ITERATIONS)
        .seed(seed)
        .method(method)
        .faults(faults)
        .on(backend)
}

fn furnace(backend: Backend, rel: &str, method: Method) {
    let film = render(backend, rel, method, Faults::NONE);
    check(&format!("{backend} {method} {rel}"), &film);
}

const HALF: &str = "scenes/furnace/diffuse_0_5.json";
const BRIGHT: &str = "scenes/furnace/diffuse_0_8.json";
const WHITE: &str = "scenes/furnace/diffuse_0_95.json";
const MIRROR: &str = "scenes/furnace/mirror_sphere.json";
const GLASS: &str = "scenes/furnace/glass_sphere.json";

on_each_backend! {
    fn bdpt_furnace_albedo_0_5_converges_to_1(backend) {
        furnace(backend, HALF, Method::Bdpt);
    }

    fn bdpt_furnace_albedo_0_95_converges_to_1(backend) {
        furnace(backend, WHITE, Method::Bdpt);
    }

    fn bdpt_mirror_sphere_in_a_furnace_converges_to_1(backend) {
        furnace(backend, MIRROR, Method::Bdpt);
    }

    fn bdpt_glass_sphere_in_a_furnace_converges_to_1(backend) {
        furnace(backend, GLASS, Method::Bdpt);
    }

    /// The test has power: BDPT with paths capped at 8 bounces loses much of the white
    /// furnace's light (ρ^9 of it for each pixel's paths, 37 % at ρ = 0.95).
    fn bdpt_furnace_rejects_a_depth_cap(backend) {
        let film = render(backend, WHITE, Method::Bdpt, DEPTH_CAP);
        assert_too_dark(&format!("{backend} BDPT with a depth cap"), &film);
    }
}

#[test]
fn bdpt_furnace_albedo_0_8_converges_to_1() {
    furnace(Backend::Cpu, BRIGHT, Method::Bdpt);
}

#[test]
fn light_tracing_furnace_albedo_0_5_converges_to_1() {
    furnace(Backend::Cpu, HALF, Method::Light);
}

#[test]
fn light_tracing_furnace_albedo_0_95_converges_to_1() {
    furnace(Backend::Cpu, WHITE, Method::Light);
}

#[test]
fn gpu_light_tracing_furnace_albedo_0_8_converges_to_1() {
    if gpu().is_none() {
        return;
    }
    furnace(Backend::Gpu, BRIGHT, Method::Light);
}

/// Light tracing sees nothing through the mirror sphere: its furnace image is too dark, as
/// `--help` says, which is why it is tested only where it is unbiased.
#[test]
fn light_tracing_cannot_see_the_mirror_sphere() {
    let film = render(Backend::Cpu, MIRROR, Method::Light, Faults::NONE);
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

/// ... and a mirror that reflects 97 % of what it should, on every subpath that meets it.
#[test]
fn bdpt_furnace_rejects_a_dim_mirror() {
    let dim = Faults {
        specular_scale: 0.97,
        ..Faults::NONE
    };
    let film = Render::file(MIRROR)
        .size(SIZE, SIZE)
        .spp(256)
        .seed(22)
        .method(Method::Bdpt)
        .faults(dim)
        .cpu();
    assert_too_dark("BDPT with a dim mirror", &film);
}
