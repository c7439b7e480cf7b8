//! Furnace tests: in a closed enclosure whose walls emit Le = 1 − ρ and reflect with albedo ρ,
//! the radiance is exactly 1 everywhere (L = Le + ρL), whatever the path does. A renderer that
//! loses energy (a depth cap, a dim mirror, wrong Fresnel or η² bookkeeping) or gains it fails.
//!
//! Statistic: the image mean over 32x32 pixels and its standard error from the per-pixel Σx²;
//! the test asserts |mean − 1| ≤ 4 s.e. per channel (false alarm 6e-5 per channel), and that the
//! s.e. is below 0.5 %, so that a 2 % error could not hide in the noise.

use crate::common::*;
use hexray::transport::faults::Faults;

const SIZE: u32 = 32;
const SPP: u32 = 256;
const SEED: u32 = 20;

fn furnace(rel: &str) {
    let film = render_cpu(rel, SIZE, SIZE, SPP, SEED, Faults::NONE);
    let (_, se) = film.image_mean();
    assert!(
        se.iter().all(|&s| s < 0.005),
        "{rel}: s.e. {se:?} too large to resolve 2 %"
    );
    assert_mean_within_4_se(&film, [1.0; 3], rel);
    assert_eq!(film.dropped(), 0, "{rel}: non-finite samples");
}

#[test]
fn furnace_albedo_0_5_converges_to_1() {
    furnace("scenes/furnace/diffuse_0_5.json");
}

#[test]
fn furnace_albedo_0_8_converges_to_1() {
    furnace("scenes/furnace/diffuse_0_8.json");
}

#[test]
fn furnace_albedo_0_95_converges_to_1() {
    furnace("scenes/furnace/diffuse_0_95.json");
}

#[test]
fn mirror_sphere_in_a_furnace_converges_to_1() {
    furnace("scenes/furnace/mirror_sphere.json");
}

#[test]
fn glass_sphere_in_a_furnace_converges_to_1() {
    furnace("scenes/furnace/glass_sphere.json");
}

/// The furnace test has power: a maximum depth of 8 bounces loses ρ^9 of the light at ρ = 0.95
/// (37 %), and the same statistic rejects it.
#[test]
fn furnace_rejects_a_depth_cap() {
    let faults = Faults {
        max_bounces: 8,
        ..Faults::NONE
    };
    let film = render_cpu(
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

/// ... and a mirror that reflects 97 % of what it should (the course report's dark mirror).
#[test]
fn furnace_rejects_a_dim_mirror() {
    let faults = Faults {
        specular_scale: 0.97,
        ..Faults::NONE
    };
    let film = render_cpu(
        "scenes/furnace/mirror_sphere.json",
        SIZE,
        SIZE,
        SPP,
        SEED,
        faults,
    );
    let (_, _, z) = image_mean_z(&film, [1.0; 3]);
    assert!(
        z.iter().all(|z| *z < -4.0),
        "a dim mirror went unnoticed: z = {z:?}"
    );
}
