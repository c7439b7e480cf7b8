//! Several shadow rays per diffuse vertex (`--light-samples N`) estimate the same image with less
//! variance in direct light. With N light samples and one BSDF sample, Veach's multi-sample MIS
//! (thesis eq. 9.13) weighs each strategy by n_i · p_i, so N enters both power-heuristic weights
//! and the NEE sum is divided by N; getting either wrong biases the image.

use crate::common::*;
use hexray::analysis::stats::{welch_blocks, MeanImage};
use hexray::film::Film;
use statrs::distribution::{ContinuousCDF, FisherSnedecor};
use std::f64::consts::PI;

/// The closed form of `tests/direct_light.rs`: L = 4 ρ Le F(1, 1).
fn direct_light_truth() -> [f64; 3] {
    let (x, y) = (1.0f64, 1.0f64);
    let sx = (1.0 + x * x).sqrt();
    let sy = (1.0 + y * y).sqrt();
    let f = 4.0 * (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI);
    let (albedo, le) = ([0.8, 0.5, 0.2], [1.0, 2.0, 4.0]);
    [0, 1, 2].map(|c| albedo[c] * le[c] * f)
}

/// Statistic: |image mean − L| ≤ 4 s.e. per channel; at 512 spp of 8x8 pixels the s.e. is
/// below 0.25 % of L. Planted error, checked by hand: leaving N out of the emission's MIS
/// weight overcounts direct light by 28 % and gives z = 117 here.
#[test]
fn four_shadow_rays_match_the_form_factor() {
    let film = Render::file("scenes/analytic/direct_light.json")
        .size(8, 8)
        .spp(512)
        .seed(3)
        .light_samples(4)
        .cpu();
    assert_mean_within_4_se(&film, direct_light_truth(), "direct light, 4 shadow rays");
}

/// The pooled within-pixel sample variance, Σ over pixels of Σ(x − m)² / Σ (n − 1), per
/// channel, and its degrees of freedom.
fn pooled_variance(film: &Film) -> ([f64; 3], f64) {
    let mut ss = [0.0; 3];
    let mut dof = 0.0;
    for p in &film.pixels {
        let n = p.n as f64;
        for (c, s) in ss.iter_mut().enumerate() {
            *s += p.sum_sq[c] - p.sum[c] * p.sum[c] / n;
        }
        dof += n - 1.0;
    }
    (ss.map(|s| s / dof), dof)
}

/// Statistic: one-sided F-test that the per-sample variance with 4 shadow rays is below the
/// variance with 1, at α = 0.01 per channel (Bonferroni over 3 channels). The two renders have
/// different seeds, so the pooled variances are independent.
#[test]
fn four_shadow_rays_lower_the_variance_of_direct_light() {
    let scene = "scenes/analytic/direct_light.json";
    let render = Render::file(scene).size(8, 8).spp(512);
    let one = render.seed(5).light_samples(1).cpu();
    let four = render.seed(6).light_samples(4).cpu();
    let (v1, d1) = pooled_variance(&one);
    let (v4, d4) = pooled_variance(&four);
    let f = FisherSnedecor::new(d1, d4).unwrap();
    for c in 0..3 {
        let ratio = v1[c] / v4[c];
        let p = f.sf(ratio);
        eprintln!(
            "channel {c}: variance 1 ray {:.3e}, 4 rays {:.3e}, ratio {ratio:.2}, p {p:.1e}",
            v1[c], v4[c]
        );
        assert!(
            p < 0.01 / 3.0,
            "channel {c}: 4 shadow rays did not lower the variance (ratio {ratio:.3}, p {p:.3})"
        );
    }
}

/// The GPU draws extra shadow rays from the same streams and weighs them the same way.
/// Statistic: the block Welch test of `tests/gpu_parity.rs` (8x8 blocks, Bonferroni α = 0.01)
/// finds no block-channel that differs, and the image means agree within 4 s.e.
#[test]
fn gpu_matches_cpu_with_three_shadow_rays() {
    if gpu().is_none() {
        return;
    }
    let render = Render::file("scenes/tncg15_room.json")
        .size(64, 64)
        .spp(64)
        .light_samples(3);
    let a = render.seed(1).cpu();
    let b = render.seed(2).gpu();
    let (ma, sa) = a.image_mean();
    let (mb, sb) = b.image_mean();
    let report = welch_blocks(
        &MeanImage::from_film(&a).blocks(8),
        &MeanImage::from_film(&b).blocks(8),
        0.01,
    );
    eprintln!(
        "3 shadow rays: {} of {} block-channels rejected (largest |t| {:.2}); means CPU {ma:.4?} GPU {mb:.4?}",
        report.rejected, report.tests, report.largest_t
    );
    assert_eq!(report.rejected, 0, "GPU and CPU differ with 3 shadow rays");
    for c in 0..3 {
        let z = (mb[c] - ma[c]) / (sa[c] * sa[c] + sb[c] * sb[c]).sqrt();
        assert!(
            z.abs() <= 4.0,
            "channel {c}: image means differ, z = {z:.2}"
        );
    }
}

/// With one shadow ray the integrator draws no numbers from the extra rays' dimension blocks:
/// the default render is bit for bit the single-light-sample render.
#[test]
fn one_shadow_ray_draws_no_extra_numbers() {
    use hexray::math::sampling::{dim_bsdf, dim_light, dim_light_extra};
    for bounce in 0..1000 {
        for j in 1..hexray::math::sampling::MAX_LIGHT_SAMPLES {
            let d = dim_light_extra(bounce, j);
            for k in 0..4000 {
                assert!(d != dim_light(k) && d != dim_bsdf(k) && d != 0);
            }
        }
    }
}
