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

pub(crate) fn check(film: &hexray::film::Film, what: &str) {
    let truth = truth();
    let (_, se) = film.image_mean();
    // Resolves a 1 % error.
    assert!(
        (0..3).all(|c| 4.0 * se[c] < 0.01 * truth[c]),
        "{what}: s.e. {se:?}"
    );
    assert_mean_within_4_se(film, truth, what);
}

pub(crate) const SCENE: &str = "scenes/analytic/direct_light.json";

#[test]
fn radiance_under_a_square_emitter_matches_the_form_factor() {
    let film = Render::file(SCENE).size(8, 8).spp(1024).seed(3).cpu();
    check(&film, "direct light");
}

on_each_backend! {
    /// BDPT takes the same light by next-event estimation, by light subpaths splatted to the
    /// camera and by connections, weighted by MIS; the sum is the form factor again. Seed 4 on
    /// the CPU, 5 on the GPU.
    fn bdpt_radiance_under_a_square_emitter_matches_the_form_factor(backend) {
        let seed = match backend {
            Backend::Cpu => 4,
            Backend::Gpu => 5,
        };
        let film = Render::file(SCENE)
            .size(8, 8)
            .spp(1024)
            .seed(seed)
            .method(Method::Bdpt)
            .on(backend);
        check(&film, &format!("{backend} direct light, BDPT"));
    }
}
