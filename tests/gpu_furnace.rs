//! The furnace tests of `tests/furnace.rs`, on the GPU backend (lavapipe in CI): in a closed
//! enclosure whose walls emit 1 − ρ and reflect ρ, the radiance is exactly 1 everywhere. The
//! statistic is the same: |image mean − 1| ≤ 4 s.e. per channel, with the s.e. below 0.5 %.

use crate::common::*;
use hexray::transport::faults::Faults;

const SIZE: u32 = 32;
const SPP: u32 = 128;
const SEED: u32 = 21;

fn furnace(rel: &str) {
    let Some(gpu) = gpu() else { return };
    let film = render_gpu(gpu, rel, SIZE, SIZE, SPP, SEED, Faults::NONE);
    let (_, se) = film.image_mean();
    assert!(
        se.iter().all(|&s| s < 0.005),
        "{rel}: s.e. {se:?} too large to resolve 2 %"
    );
    assert_mean_within_4_se(&film, [1.0; 3], &format!("GPU {rel}"));
    assert_eq!(film.dropped(), 0, "{rel}: non-finite samples");
}

#[test]
fn gpu_furnace_albedo_0_5_converges_to_1() {
    furnace("scenes/furnace/diffuse_0_5.json");
}

#[test]
fn gpu_furnace_albedo_0_8_converges_to_1() {
    furnace("scenes/furnace/diffuse_0_8.json");
}

#[test]
fn gpu_furnace_albedo_0_95_converges_to_1() {
    furnace("scenes/furnace/diffuse_0_95.json");
}

#[test]
fn gpu_mirror_sphere_in_a_furnace_converges_to_1() {
    furnace("scenes/furnace/mirror_sphere.json");
}

#[test]
fn gpu_glass_sphere_in_a_furnace_converges_to_1() {
    furnace("scenes/furnace/glass_sphere.json");
}

/// Power on the GPU too: the planted depth cap is rejected by the same statistic.
#[test]
fn gpu_furnace_rejects_a_depth_cap() {
    let Some(gpu) = gpu() else { return };
    let faults = Faults {
        max_bounces: 8,
        ..Faults::NONE
    };
    let film = render_gpu(
        gpu,
        "scenes/furnace/diffuse_0_95.json",
        SIZE,
        SIZE,
        SPP,
        SEED,
        faults,
    );
    let (_, _, z) = image_mean_z(&film, [1.0; 3]);
    assert!(
        z.iter().all(|z| *z < -4.0),
        "a depth cap went unnoticed: z = {z:?}"
    );
}
