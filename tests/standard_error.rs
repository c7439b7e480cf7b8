//! The standard error a film reports is the real one: the scatter of image means across
//! independent seeds equals the s.e. each render claims from its own Σx² (so every z-score in
//! the other tests is on the right scale).
//!
//! Statistic: with k = 100 independent renders, (k − 1) · s² / σ̂² follows χ²(k − 1), where s is
//! the sample standard deviation of the k image means and σ̂² the mean claimed variance (each
//! claimed s.e. is itself estimated from 16 · 256 samples, so its own scatter is negligible).
//! Two-sided at α = 0.01: χ²(99) quantiles 66.5 and 139.0, so a claimed variance off by a
//! factor 2 either way (statistic 49.5 or 198 in expectation) is rejected.

use crate::common::*;
use hexray::cpu::Faults;
use statrs::distribution::{ChiSquared, ContinuousCDF};

#[test]
fn film_standard_error_matches_the_scatter_across_seeds() {
    let k = 100;
    let (means, claimed): (Vec<f64>, Vec<f64>) = (100..100 + k)
        .map(|seed| {
            let film = render_cpu("scenes/cornell_box.json", 16, 16, 16, seed, Faults::NONE);
            let (m, se) = film.image_mean();
            (m[0], se[0] * se[0])
        })
        .unzip();
    let n = k as f64;
    let mean = means.iter().sum::<f64>() / n;
    let s2 = means.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let claimed = claimed.iter().sum::<f64>() / n;
    let stat = (n - 1.0) * s2 / claimed;
    let chi = ChiSquared::new(n - 1.0).unwrap();
    let (lo, hi) = (chi.inverse_cdf(0.005), chi.inverse_cdf(0.995));
    eprintln!(
        "scatter s.d. {:.3e}, claimed s.e. {:.3e}, ratio {:.3}; statistic {stat:.2} in [{lo:.2}, {hi:.2}]",
        s2.sqrt(),
        claimed.sqrt(),
        (s2 / claimed).sqrt()
    );
    assert!(
        (lo..=hi).contains(&stat),
        "the claimed standard error does not match the scatter across seeds: χ² = {stat:.2}"
    );
}
