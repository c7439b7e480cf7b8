//! The standard error a film reports is the real one: the scatter of image means across
//! independent seeds equals the s.e. each render claims from its own Σx² (so every z-score in
//! the other tests is on the right scale).
//!
//! Statistic: with k independent renders, (k − 1) · s² / σ̂² follows χ²(k − 1), where s is the
//! sample standard deviation of the k image means and σ̂² the mean claimed variance (each
//! claimed s.e. is itself estimated from many samples, so its own scatter is small). Two-sided
//! at α = 0.01: for k = 100, χ²(99) quantiles 66.5 and 139.0, so a claimed variance off by a
//! factor 2 either way (statistic 49.5 or 198 in expectation) is rejected.
//!
//! Light tracing and BDPT splat one light subpath into several pixels, so their pixels are not
//! independent within an iteration; their films claim the image mean's s.e. from the scatter of
//! the iterations' image means (batch means, `Film::iteration_means`), and the same statistic
//! checks that claim. The pixel-independent formula, which ignores what pixels share, is shown
//! to be rejected for light tracing: that is why the batch means are there.

use crate::common::*;
use hexray::film::Film;
use hexray::transport::method::Method;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// The χ² statistic of k image means (red channel) against their mean claimed variance, and
/// whether it lies within the two-sided 99 % interval.
pub(crate) fn chi_square_of_scatter(what: &str, means_and_claims: &[(f64, f64)]) -> (f64, bool) {
    let n = means_and_claims.len() as f64;
    let mean = means_and_claims.iter().map(|m| m.0).sum::<f64>() / n;
    let s2 = means_and_claims
        .iter()
        .map(|m| (m.0 - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0);
    let claimed = means_and_claims.iter().map(|m| m.1).sum::<f64>() / n;
    let stat = (n - 1.0) * s2 / claimed;
    let chi = ChiSquared::new(n - 1.0).unwrap();
    let (lo, hi) = (chi.inverse_cdf(0.005), chi.inverse_cdf(0.995));
    eprintln!(
        "{what}: scatter s.d. {:.3e}, claimed s.e. {:.3e}, ratio {:.3}; statistic {stat:.2} in [{lo:.2}, {hi:.2}]",
        s2.sqrt(),
        claimed.sqrt(),
        (s2 / claimed).sqrt()
    );
    (stat, (lo..=hi).contains(&stat))
}

/// The pixel-independent variance of the image mean, Σ var / P²: right for path tracing, not
/// for methods whose pixels share samples.
fn pixel_independent_variance(film: &Film) -> f64 {
    let p = film.pixels.len() as f64;
    film.pixels.iter().map(|x| x.var_of_mean()[0]).sum::<f64>() / (p * p)
}

#[test]
fn film_standard_error_matches_the_scatter_across_seeds() {
    let renders: Vec<(f64, f64)> = (100..200)
        .map(|seed| {
            let film = Render::file("scenes/cornell_box.json")
                .size(16, 16)
                .spp(16)
                .seed(seed)
                .cpu();
            let (m, se) = film.image_mean();
            (m[0], se[0] * se[0])
        })
        .collect();
    let (stat, ok) = chi_square_of_scatter("path", &renders);
    assert!(
        ok,
        "the claimed standard error does not match the scatter across seeds: χ² = {stat:.2}"
    );
}

/// 400 renders of `method` on cornell_box (16x16, 32 iterations, seeds 300 to 699), rendered
/// once per test binary. k = 400 rather than 100: χ²(399)'s two-sided 99 % interval is ±18 %
/// of its mean, χ²(99)'s ±35 %, so a claimed variance 30 % off is rejected too.
fn films(method: Method) -> &'static [Film] {
    use std::sync::OnceLock;
    static LIGHT: OnceLock<Vec<Film>> = OnceLock::new();
    static BDPT: OnceLock<Vec<Film>> = OnceLock::new();
    let cell = if method == Method::Light {
        &LIGHT
    } else {
        &BDPT
    };
    cell.get_or_init(|| {
        (300..700)
            .map(|seed| {
                Render::file("scenes/cornell_box.json")
                    .size(16, 16)
                    .spp(32)
                    .seed(seed)
                    .method(method)
                    .cpu()
            })
            .collect()
    })
}

/// [`films`] as (image mean, claimed batch-means variance, pixel-independent variance), red
/// channel.
fn renders(method: Method) -> Vec<(f64, f64, f64)> {
    films(method)
        .iter()
        .map(|film| {
            let (m, se) = film.image_mean();
            (m[0], se[0] * se[0], pixel_independent_variance(film))
        })
        .collect()
}

#[test]
fn bdpt_batch_means_standard_error_matches_the_scatter_across_seeds() {
    let r: Vec<(f64, f64)> = renders(Method::Bdpt).iter().map(|x| (x.0, x.1)).collect();
    let (stat, ok) = chi_square_of_scatter("bdpt, batch means", &r);
    assert!(ok, "BDPT's claimed standard error is off: χ² = {stat:.2}");
}

#[test]
fn light_tracing_batch_means_standard_error_matches_the_scatter_across_seeds() {
    let r: Vec<(f64, f64)> = renders(Method::Light).iter().map(|x| (x.0, x.1)).collect();
    let (stat, ok) = chi_square_of_scatter("light, batch means", &r);
    assert!(
        ok,
        "light tracing's claimed standard error is off: χ² = {stat:.2}"
    );
}

/// The check has power where it matters: light tracing's image mean with the pixel-independent
/// variance (what a film without batch means would claim) is rejected.
#[test]
fn standard_error_check_rejects_pixel_independent_errors_for_light_tracing() {
    let r: Vec<(f64, f64)> = renders(Method::Light).iter().map(|x| (x.0, x.2)).collect();
    let (stat, ok) = chi_square_of_scatter("light, pixels as if independent", &r);
    assert!(
        !ok,
        "the pixel-independent s.e. went unnoticed: χ² = {stat:.2}"
    );
}

/// The block tests (`stats::welch_blocks`, `against_truth`) sum pixel variances over an 8x8
/// block as if its pixels were independent. For BDPT that is close enough: per 8x8 block of the
/// same 400 renders, the scatter of the block means across seeds matches the summed claim
/// (χ²(399) within its two-sided 99 % interval, Bonferroni over the 4 blocks).
#[test]
fn bdpt_block_standard_errors_match_the_scatter_across_seeds() {
    let films = films(Method::Bdpt);
    for block in 0..4u32 {
        let (bx, by) = (8 * (block % 2), 8 * (block / 2));
        let r: Vec<(f64, f64)> = films
            .iter()
            .map(|f| {
                let (mut m, mut v) = (0.0, 0.0);
                for y in by..by + 8 {
                    for x in bx..bx + 8 {
                        let p = &f.pixels[(y * 16 + x) as usize];
                        m += p.mean()[0] / 64.0;
                        v += p.var_of_mean()[0] / (64.0 * 64.0);
                    }
                }
                (m, v)
            })
            .collect();
        let n = r.len() as f64;
        let mean = r.iter().map(|m| m.0).sum::<f64>() / n;
        let s2 = r.iter().map(|m| (m.0 - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let claimed = r.iter().map(|m| m.1).sum::<f64>() / n;
        let stat = (n - 1.0) * s2 / claimed;
        let chi = ChiSquared::new(n - 1.0).unwrap();
        let (lo, hi) = (
            chi.inverse_cdf(0.005 / 4.0),
            chi.inverse_cdf(1.0 - 0.005 / 4.0),
        );
        eprintln!(
            "bdpt block {block}: scatter/claimed s.d. ratio {:.3}, statistic {stat:.1} in [{lo:.1}, {hi:.1}]",
            (s2 / claimed).sqrt()
        );
        assert!((lo..=hi).contains(&stat), "block {block}: χ² = {stat:.1}");
    }
}
