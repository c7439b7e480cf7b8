//! Direct light against a closed form: a diffuse plane of albedo ρ under a square emitter of
//! radiance Le, both parallel, the emitter's centre at height h above the origin.
//!
//! The radiance leaving the origin is L = ρ/π · E and the irradiance is E = π Le F, where F is
//! the form factor from a differential area to a parallel rectangle. For a rectangle with a
//! corner above the point, sides a and b at height h (X = a/h, Y = b/h):
//! F = 1/(2π) [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))]
//! (Howell's catalogue of configuration factors, C-11); the centred square is four such
//! rectangles. So L = 4 ρ Le F(1, 1) here.
//!
//! Statistic: |image mean − L| ≤ 4 s.e. per channel.

use crate::common::*;
use hexray::transport::faults::Faults;
use hexray::transport::method::Method;
use std::f64::consts::PI;

fn corner_form_factor(x: f64, y: f64) -> f64 {
    let sx = (1.0 + x * x).sqrt();
    let sy = (1.0 + y * y).sqrt();
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

/// The exact image mean, 4 ρ Le F(1, 1) per channel.
fn truth() -> [f64; 3] {
    let f = 4.0 * corner_form_factor(1.0, 1.0);
    let (albedo, le) = ([0.8, 0.5, 0.2], [1.0, 2.0, 4.0]);
    [0, 1, 2].map(|c| albedo[c] * le[c] * f)
}

fn check(film: &hexray::film::Film, what: &str) {
    let truth = truth();
    let (_, se) = film.image_mean();
    // Resolves a 1 % error.
    assert!(
        (0..3).all(|c| 4.0 * se[c] < 0.01 * truth[c]),
        "{what}: s.e. {se:?}"
    );
    assert_mean_within_4_se(film, truth, what);
}

const SCENE: &str = "scenes/analytic/direct_light.json";

#[test]
fn radiance_under_a_square_emitter_matches_the_form_factor() {
    let film = render_cpu(SCENE, 8, 8, 1024, 3, Faults::NONE);
    check(&film, "direct light");
}

/// BDPT takes the same light by next-event estimation, by light subpaths splatted to the
/// camera and by connections, weighted by MIS; the sum is the form factor again.
#[test]
fn bdpt_radiance_under_a_square_emitter_matches_the_form_factor() {
    let film = render_cpu_method(SCENE, 8, 8, 1024, 4, Method::Bdpt, Faults::NONE);
    check(&film, "direct light, BDPT");
}

#[test]
fn gpu_bdpt_radiance_under_a_square_emitter_matches_the_form_factor() {
    let Some(gpu) = gpu() else { return };
    let film = render_gpu_method(gpu, SCENE, 8, 8, 1024, 5, Method::Bdpt, Faults::NONE);
    check(&film, "GPU direct light, BDPT");
}
