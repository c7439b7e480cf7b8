//! Furnace tests: in a closed enclosure whose walls emit Le = 1 − ρ and reflect with albedo ρ,
//! the radiance is exactly 1 everywhere (L = Le + ρL), whatever the path does. A renderer that
//! loses energy (a depth cap, a dim mirror, wrong Fresnel or η² bookkeeping) or gains it fails.
//! Each test runs on each backend that it names (the GPU: lavapipe in CI).
//!
//! Statistic: the image mean over 32x32 pixels and its standard error from the per-pixel Σx²;
//! the test asserts |mean − 1| ≤ 4 s.e. per channel (false alarm 6e-5 per channel), and that the
//! s.e. is below 0.5 %, so that a 2 % error could not hide in the noise.

use crate::common::*;
use hexray::film::Film;
use hexray::transport::faults::Faults;

const SIZE: u32 = 32;

/// The furnace render of `rel` on `backend`: 256 samples per pixel, seed 20 on the CPU; 128,
/// seed 21 on the GPU.
fn render(backend: Backend, rel: &str, faults: Faults) -> Film {
    let (spp, seed) = match backend {
        Backend::Cpu => (256, 20),
        Backend::Gpu => (128, 21),
    };
    Render::file(rel)
        .size(SIZE, SIZE)
        .spp(spp)
        .seed(seed)
        .faults(faults)
        .on(backend)
}

fn furnace(backend: Backend, rel: &str) {
    let film = render(backend, rel, Faults::NONE);
    let (_, se) = film.image_mean();
    assert!(
        se.iter().all(|&s| s < 0.005),
        "{backend} {rel}: s.e. {se:?} too large to resolve 2 %"
    );
    assert_mean_within_4_se(&film, [1.0; 3], &format!("{backend} {rel}"));
    assert_eq!(film.dropped(), 0, "{backend} {rel}: non-finite samples");
}

on_each_backend! {
    fn furnace_albedo_0_5_converges_to_1(backend) {
        furnace(backend, "scenes/furnace/diffuse_0_5.json");
    }

    fn furnace_albedo_0_8_converges_to_1(backend) {
        furnace(backend, "scenes/furnace/diffuse_0_8.json");
    }

    fn furnace_albedo_0_95_converges_to_1(backend) {
        furnace(backend, "scenes/furnace/diffuse_0_95.json");
    }

    fn mirror_sphere_in_a_furnace_converges_to_1(backend) {
        furnace(backend, "scenes/furnace/mirror_sphere.json");
    }

    fn glass_sphere_in_a_furnace_converges_to_1(backend) {
        furnace(backend, "scenes/furnace/glass_sphere.json");
    }

    /// The furnace test has power: a maximum depth of 8 bounces loses ρ^9 of the light at
    /// ρ = 0.95 (37 %), and the same statistic rejects it.
    fn furnace_rejects_a_depth_cap(backend) {
        let faults = Faults {
            max_bounces: 8,
            ..Faults::NONE
        };
        let film = render(backend, "scenes/furnace/diffuse_0_95.json", faults);
        let (_, _, z) = image_mean_z(&film, [1.0; 3]);
        assert!(
            z.iter().all(|z| *z < -4.0),
            "{backend}: a depth cap went unnoticed: z = {z:?}"
        );
    }
}

/// ... and a mirror that reflects 97 % of what it should (the course report's dark mirror).
#[test]
fn furnace_rejects_a_dim_mirror() {
    let faults = Faults {
        specular_scale: 0.97,
        ..Faults::NONE
    };
    let film = render(Backend::Cpu, "scenes/furnace/mirror_sphere.json", faults);
    let (_, _, z) = image_mean_z(&film, [1.0; 3]);
    assert!(
        z.iter().all(|z| *z < -4.0),
        "a dim mirror went unnoticed: z = {z:?}"
    );
}
