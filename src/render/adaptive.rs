//! Adaptive sampling (`--adaptive`): rounds whose per-pixel sample counts follow the error
//! measured before them, each sample weighted so that the image stays unbiased.
//!
//! **Rounds and weights.** Round k spends B_k samples per pixel on average. Pixel p draws
//! n_{k,p} of them, decided from the film as it stood before the round (the samples of rounds
//! 0..k−1 only), and each of them weighs c_{k,p} = B_k / n_{k,p}, fixed before it is drawn. The
//! pixel's estimate Σcx / Σc ([`crate::film::PixelStats::mean`]) is then, over whole rounds,
//!
//!   m_p = Σ_k (B_k / Σ_j B_j) m_{k,p},
//!
//! a mean of the round means with weights fixed in advance, each round mean unbiased given its
//! count, which its own samples did not decide. A round cut short (a stop, a time budget) keeps
//! the weights it was planned with: still a fixed-weight mean of unbiased batch means.
//! Averaging the same samples with weight 1 instead ("pooling") is biased: a pixel whose first
//! samples missed a rare bright path looks converged, gets fewer samples and stays dark, while
//! one that met it early has it diluted. The planted fault `Faults::adaptive_pooled` does that,
//! and the tests reject it.
//!
//! **Counts.** A pixel's need is its relative variance per sample, the relMSE's terms:
//!
//!   v_p = Σ_c σ²_{p,c} / (m²_{p,c} + 0.01),
//!
//! with σ² the variance of the mean ([`crate::film::Film::var_of_mean`]) times the pixel's
//! effective sample count. At a fixed total, Σ_p v_p / n_p (the relMSE) is least at n_p ∝ √v_p.
//! A pixel's own estimate from a few samples is mostly noise (a caustic pixel whose samples all
//! missed looks black and certain), so the need is averaged over a (2R + 1)² box of pixels
//! first, and a share F of each round is spread evenly, so that no pixel starves on an estimate
//! that missed its light. Counts are even, so that the sampler's two streams keep equal shares,
//! and at least 2.
//!
//! **Schedule.** Round 0 is uniform, N/8 samples per pixel of a budget of N (8 under a time
//! budget); each later round spends as many as all rounds before it, so the counts are decided
//! from at least half of the samples, and the last is cut to the budget.

use super::{pass_size, Backend, Budget, ErrorTarget, FirstPass, RenderReport, StopReason};
pub use crate::film::PixelRun;
use crate::film::{Film, RELMSE_EPSILON};
use crate::math::sampling::pcg4d;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// How adaptive sampling spends a round.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveSettings {
    /// The share F of each round spread evenly over the pixels.
    pub floor: f64,
    /// The half-width R of the box the need is averaged over, as a share of the image's
    /// larger side (at least 2 pixels).
    pub blur: f64,
}

impl Default for AdaptiveSettings {
    /// F = 0.25, R = 1/16 of the larger side: measured on mirror_caustic and tncg15_room
    /// (docs/sampling.md).
    fn default() -> Self {
        AdaptiveSettings {
            floor: 0.25,
            blur: 1.0 / 16.0,
        }
    }
}

impl AdaptiveSettings {
    /// R in pixels for a `width` x `height` image (0 for a share of 0: each pixel's own need).
    pub fn blur_pixels(&self, width: u32, height: u32) -> u32 {
        if self.blur <= 0.0 {
            return 0;
        }
        ((width.max(height) as f64 * self.blur).round() as u32).max(2)
    }
}

/// Round 0's samples per pixel under a time budget, and at least under a sample budget.
pub const WARM_UP_SPP: u32 = 8;

/// A round: its budget B (samples per pixel on average), each pixel's count n_p and the sample
/// index it started the round at.
#[derive(Clone, Debug, PartialEq)]
pub struct Round {
    pub budget: u32,
    pub counts: Vec<u32>,
    pub starts: Vec<u32>,
}

/// Samples taken so far by pixel `p` (accumulated and dropped).
fn taken(film: &Film, p: usize) -> u32 {
    let s = &film.pixels[p];
    (s.n + s.dropped) as u32
}

impl Round {
    /// Every pixel `budget` samples (rounded up to even).
    pub fn uniform(film: &Film, budget: u32) -> Round {
        let n = budget.max(2).next_multiple_of(2);
        Round {
            budget,
            counts: vec![n; film.pixels.len()],
            starts: (0..film.pixels.len()).map(|p| taken(film, p)).collect(),
        }
    }

    /// Round `index` of `budget` samples per pixel on average, each pixel's count from the
    /// film's error so far (the module's text).
    pub fn plan(film: &Film, budget: u32, index: u32, settings: AdaptiveSettings) -> Round {
        let r = settings.blur_pixels(film.width, film.height);
        let need = blurred(&need(film), film.width, film.height, r);
        let root: Vec<f64> = need.iter().map(|v| v.sqrt()).collect();
        let mean_root = root.iter().sum::<f64>() / root.len().max(1) as f64;
        let counts = root
            .iter()
            .enumerate()
            .map(|(p, &r)| {
                let share = if mean_root > 0.0 {
                    settings.floor + (1.0 - settings.floor) * r / mean_root
                } else {
                    1.0
                };
                // Half the count, rounded at random (a hash of the pixel and the round, not
                // of the samples) so that the round spends its budget on average.
                let half = budget as f64 * share / 2.0;
                let u = pcg4d([p as u32, index, 0x0ada_9717, 0])[0] as f64 / 4294967296.0;
                let half = half.floor() + f64::from(u8::from(u < half.fract()));
                (2.0 * half).clamp(2.0, u32::MAX as f64 / 4.0) as u32
            })
            .collect();
        Round {
            budget,
            counts,
            starts: (0..film.pixels.len()).map(|p| taken(film, p)).collect(),
        }
    }

    /// The weight of pixel `p`'s samples in this round, c = B / n_p.
    pub fn weight(&self, p: usize) -> f64 {
        self.budget as f64 / self.counts[p] as f64
    }

    /// The samples due by the share `phi` of the round that `film` does not have yet: pixel p
    /// has 2 ⌊φ n_p / 2⌋ of its n_p by then (all of them at φ = 1).
    pub fn runs(&self, film: &Film, phi: f64) -> Vec<PixelRun> {
        let mut out = Vec::new();
        for (p, (&n, &start)) in self.counts.iter().zip(&self.starts).enumerate() {
            let due = if phi >= 1.0 {
                n
            } else {
                2 * ((phi * n as f64 / 2.0).floor() as u32).min(n / 2)
            };
            let have = taken(film, p) - start;
            if due > have {
                out.push(PixelRun {
                    pixel: p as u32,
                    first: start + have,
                    count: due - have,
                    weight: self.weight(p),
                });
            }
        }
        out
    }
}

/// Each pixel's relative variance per sample, Σ_c σ² / (m² + ε).
fn need(film: &Film) -> Vec<f64> {
    film.pixels
        .iter()
        .map(|p| {
            let (m, v) = (p.mean(), film.var_of_mean(p));
            let n_eff = if p.w_sq > 0.0 {
                p.w * p.w / p.w_sq
            } else {
                0.0
            };
            (0..3)
                .map(|c| v[c] * n_eff / (m[c] * m[c] + RELMSE_EPSILON))
                .sum::<f64>()
        })
        .collect()
}

/// The mean of `values` (a `width` x `height` image) over the box of half-width `r` around each
/// pixel, clipped at the image's edges: along rows, then along columns, each from prefix sums.
fn blurred(values: &[f64], width: u32, height: u32, r: u32) -> Vec<f64> {
    let (w, h, r) = (width as usize, height as usize, r as usize);
    // The box mean of a line of `len` values at stride `step` from `at`, into `out`.
    let line = |src: &[f64], out: &mut [f64], at: usize, step: usize, len: usize| {
        let mut prefix = Vec::with_capacity(len + 1);
        prefix.push(0.0);
        for i in 0..len {
            prefix.push(prefix[i] + src[at + i * step]);
        }
        for i in 0..len {
            let (a, z) = (i.saturating_sub(r), (i + r + 1).min(len));
            out[at + i * step] = (prefix[z] - prefix[a]) / (z - a) as f64;
        }
    };
    let mut rows = vec![0.0; w * h];
    for y in 0..h {
        line(values, &mut rows, y * w, 1, w);
    }
    let mut out = vec![0.0; w * h];
    for x in 0..w {
        line(&rows, &mut out, x, w, h);
    }
    out
}

/// [`super::render_progressive`] with adaptive sampling: rounds (the module's text) in passes
/// of about the same duration, until the budget is spent (samples per pixel on average),
/// `stop` is set or the backend fails. `on_pass(film, spp_done, elapsed)` after each pass, with
/// the samples per pixel spent so far on average.
pub fn render_adaptive(
    backend: &mut dyn Backend,
    film: &mut Film,
    budget: Budget,
    settings: AdaptiveSettings,
    stop: &AtomicBool,
    mut on_pass: impl FnMut(&Film, u32, f64),
) -> RenderReport {
    assert!(budget.spp.is_some() || budget.seconds.is_some() || budget.relmse.is_some());
    let start = Instant::now();
    // Samples per pixel spent so far, whole rounds and the share of the current one.
    let mut done = film.mean_spp();
    let target = budget.spp.map(|s| done + s as f64);
    let mut round: Option<(Round, f64)> = None;
    let mut rounds = 0u32;
    let mut per_spp = None::<f64>;
    let mut first_pass = None;
    let reason = loop {
        if stop.load(Ordering::SeqCst) {
            break StopReason::Interrupted;
        }
        let elapsed = start.elapsed().as_secs_f64();
        if target.is_some_and(|t| done >= t - 0.5) {
            break StopReason::SampleCount;
        }
        if budget.seconds.is_some_and(|s| elapsed >= s) {
            break StopReason::TimeBudget;
        }
        let needed = match super::error_target(film, budget, done as u32) {
            ErrorTarget::Reached => break StopReason::ErrorTarget,
            ErrorTarget::Needs(n) => n,
        };
        // The next round, once the last is spent.
        if round.as_ref().is_none_or(|(_, phi)| *phi >= 1.0) {
            let warm_up = film.mean_spp() == 0.0;
            let mut b = if warm_up {
                target.map_or(WARM_UP_SPP, |t| ((t / 8.0) as u32).max(WARM_UP_SPP))
            } else {
                (done.round() as u32).max(2)
            };
            if let Some(t) = target {
                b = b.min((t - done).round().max(1.0) as u32);
            }
            let r = if warm_up {
                Round::uniform(film, b)
            } else {
                Round::plan(film, b, rounds, settings)
            };
            rounds += 1;
            round = Some((r, 0.0));
        }
        let (r, phi) = round.as_mut().expect("planned above");
        // The pass: as many samples per pixel on average as fit its duration.
        let remaining = ((1.0 - *phi) * r.budget as f64).ceil() as u32;
        let count = pass_size(per_spp, budget, elapsed, Some(remaining), needed);
        let next = (*phi + count as f64 / r.budget as f64).min(1.0);
        let runs = r.runs(film, next);
        let t0 = Instant::now();
        let before = film.mean_spp();
        if let Err(e) = backend.adaptive_pass_until(&runs, film, stop) {
            break StopReason::Failed(format!("{e:#}"));
        }
        let wanted: u64 = runs.iter().map(|r| r.count as u64).sum();
        if wanted > 0 && film.mean_spp() == before {
            // Stopped under way: the pass was dropped whole.
            break StopReason::Interrupted;
        }
        // The cost of a sample per pixel, from the samples the pass took (none where every
        // pixel's share rounded down to nothing: the next pass is sized as the first).
        if wanted > 0 {
            let spp = wanted as f64 / film.pixels.len() as f64;
            let seconds = t0.elapsed().as_secs_f64();
            per_spp = Some(seconds / spp);
            first_pass.get_or_insert(FirstPass { spp, seconds });
        }
        done += (next - *phi) * r.budget as f64;
        *phi = next;
        on_pass(film, done.round() as u32, start.elapsed().as_secs_f64());
    };
    RenderReport {
        spp: done.round() as u32,
        seconds: start.elapsed().as_secs_f64(),
        reason,
        first_pass,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A film whose left half is noisy and right half constant.
    fn half_noisy(width: u32, height: u32, spp: u32) -> Film {
        let mut f = Film::new(width, height);
        for (i, p) in f.pixels.iter_mut().enumerate() {
            let noisy = (i as u32 % width) < width / 2;
            for s in 0..spp {
                let x = if noisy { (s % 2) as f32 * 2.0 } else { 1.0 };
                p.add(Vec3::splat(x));
            }
        }
        f
    }

    #[test]
    fn a_round_spends_its_budget_on_average_in_even_counts() {
        let film = half_noisy(32, 16, 8);
        let r = Round::plan(&film, 16, 1, AdaptiveSettings::default());
        let mean = r.counts.iter().sum::<u32>() as f64 / r.counts.len() as f64;
        assert!((mean - 16.0).abs() < 0.5, "{mean}");
        assert!(r.counts.iter().all(|&n| n >= 2 && n % 2 == 0));
    }

    #[test]
    fn noisy_pixels_get_more_samples_and_quiet_ones_the_floor() {
        let film = half_noisy(32, 16, 8);
        let r = Round::plan(&film, 16, 1, AdaptiveSettings::default());
        // Far from the border (the blur's reach), the quiet half gets F of the budget.
        // (R = 2 pixels at 32 x 16.)
        let (noisy, quiet) = (r.counts[8 * 32 + 2], r.counts[8 * 32 + 29]);
        assert!(noisy > 24 && (2..=6).contains(&quiet), "{noisy} {quiet}");
    }

    #[test]
    fn the_blur_is_the_box_mean_clipped_at_the_edges() {
        let v: Vec<f64> = (0..12).map(|i| (i * i) as f64).collect();
        let b = blurred(&v, 4, 3, 1);
        // Pixel (0, 0): the mean of (0, 0), (1, 0), (0, 1), (1, 1) = (0 + 1 + 16 + 25) / 4.
        assert!((b[0] - 10.5).abs() < 1e-12);
        // Pixel (1, 1): the 3 x 3 box of values at 0, 1, 2, 4, 5, 6, 8, 9, 10.
        let want = [0, 1, 2, 4, 5, 6, 8, 9, 10]
            .iter()
            .map(|&i| (i * i) as f64)
            .sum::<f64>()
            / 9.0;
        assert!((b[5] - want).abs() < 1e-12);
    }

    #[test]
    fn the_runs_of_a_round_add_up_to_its_counts() {
        let mut film = half_noisy(8, 4, 4);
        let r = Round::plan(&film, 10, 1, AdaptiveSettings::default());
        for phi in [0.3, 0.7, 1.0] {
            for run in r.runs(&film, phi) {
                assert_eq!(run.first % 2, 0);
                let p = &mut film.pixels[run.pixel as usize];
                for _ in 0..run.count {
                    p.add(Vec3::ONE);
                }
            }
        }
        for (p, s) in film.pixels.iter().enumerate() {
            assert_eq!(s.n as u32, r.starts[p] + r.counts[p]);
        }
        assert!(r.runs(&film, 1.0).is_empty());
    }
}
