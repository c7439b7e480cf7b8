//! The film: per-pixel sums of samples and of their squares, so that every image carries its own
//! standard error.
//!
//! A pixel's estimate is the sample mean m = Σx / n, and the variance of that mean is estimated
//! without bias by (Σx² − (Σx)²/n) / (n (n − 1)). Sums are kept in f64: at 10^5 samples an f32
//! sum has lost about 17 of its 24 bits to the magnitude of the running total.
//!
//! Adaptive sampling (`crate::render::adaptive`) gives each sample a weight c fixed before the
//! sample is drawn; the estimate is then the weighted mean m = Σcx / Σc, and the sums are of cx
//! and (cx)², with Σc and Σc² beside them. Unweighted samples have c = 1, where every formula
//! below is the plain one.

use crate::math::sampling::SamplerKind;
use glam::Vec3;

pub mod file;
pub mod output;
pub mod parts;
pub mod provenance;

/// The accumulated samples of one pixel. A sample that is not finite is counted in `dropped` and
/// contributes nothing else: one NaN must not erase a pixel's other samples.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelStats {
    pub sum: [f64; 3],
    pub sum_sq: [f64; 3],
    /// Samples that were accumulated.
    pub n: u64,
    /// Samples that were not finite and were dropped.
    pub dropped: u64,
    /// The sum and count of the accumulated samples of even index (0, 2, 4, ...): under the
    /// Sobol sampler, one of the pixel's two independent streams (`SamplerKind`), from which
    /// [`PixelStats::var_of_mean_from_streams`] estimates the mean's error.
    pub even_sum: [f64; 3],
    pub even_n: u64,
    /// The sums of the accumulated samples' weights (Σc, Σc²) and of the even-index ones'
    /// (equal to n, n and even_n where every weight is 1).
    pub w: f64,
    pub w_sq: f64,
    pub even_w: f64,
}

impl PixelStats {
    /// Adds the pixel's next sample, or counts it as dropped when any channel is NaN or
    /// infinite. Samples come in sample order (the renderers add them so), so the sample's
    /// index is the count so far, `n + dropped`.
    #[inline]
    pub fn add(&mut self, x: Vec3) {
        let even = (self.n + self.dropped).is_multiple_of(2);
        if !x.is_finite() {
            self.dropped += 1;
            return;
        }
        for c in 0..3 {
            let v = x[c] as f64;
            self.sum[c] += v;
            self.sum_sq[c] += v * v;
            if even {
                self.even_sum[c] += v;
            }
        }
        self.n += 1;
        self.even_n += u64::from(even);
        self.w += 1.0;
        self.w_sq += 1.0;
        self.even_w += f64::from(u8::from(even));
    }

    /// Folds in another set of sums (a later batch of samples of the same pixel).
    #[inline]
    pub fn merge(&mut self, o: &PixelStats) {
        self.merge_weighted(o, 1.0);
    }

    /// Folds in a later batch of samples of the same pixel, each weighted by `c` (adaptive
    /// sampling's fixed weight of the batch's samples): Σx becomes Σcx, Σx² becomes Σ(cx)².
    /// The batch must start at an even sample index (its even samples are then the pixel's).
    #[inline]
    pub fn merge_weighted(&mut self, o: &PixelStats, c: f64) {
        for k in 0..3 {
            self.sum[k] += c * o.sum[k];
            self.sum_sq[k] += c * c * o.sum_sq[k];
            self.even_sum[k] += c * o.even_sum[k];
        }
        self.n += o.n;
        self.dropped += o.dropped;
        self.even_n += o.even_n;
        self.w += c * o.w;
        self.w_sq += c * c * o.w_sq;
        self.even_w += c * o.even_w;
    }

    /// The (weighted) mean Σcx / Σc.
    pub fn mean(&self) -> [f64; 3] {
        if self.n == 0 || self.w <= 0.0 {
            return [0.0; 3];
        }
        self.sum.map(|s| s / self.w)
    }

    /// The estimated variance of the mean (the squared standard error), per channel. For
    /// weighted samples of one variance σ², Var(Σcx / Σc) = σ² Σc² / (Σc)², and
    /// (Σ(cx)² − m² Σc²) / (Σc)² estimates it times (1 − 1 / n_eff), n_eff = (Σc)² / Σc²; with
    /// every c = 1 this is (Σx² − (Σx)²/n) / (n (n − 1)).
    pub fn var_of_mean(&self) -> [f64; 3] {
        if self.n < 2 || self.w <= 0.0 {
            return [0.0; 3];
        }
        let (w, w_sq) = (self.w, self.w_sq);
        let n_eff = w * w / w_sq;
        if n_eff <= 1.0 {
            return [0.0; 3];
        }
        std::array::from_fn(|c| {
            let ss = self.sum_sq[c] - self.sum[c] * self.sum[c] * w_sq / (w * w);
            ss.max(0.0) / (w * w) * n_eff / (n_eff - 1.0)
        })
    }

    /// The estimated variance of the mean from the pixel's two independent streams, the
    /// samples of even and of odd index (`SamplerKind::Sobol`): with stream means e and o over
    /// n_e and n_o samples, (e − o)² n_e n_o / n², unbiased where each stream's variance
    /// falls as one over its count (and exactly (e − o)² / 4 for equal counts, whatever the
    /// rate). One degree of freedom per pixel: right on average over many pixels (an image's
    /// error), too rough to judge one pixel by. Zero before one sample in each stream.
    /// Weighted samples (adaptive sampling) take each stream's weight sum for its count.
    pub fn var_of_mean_from_streams(&self) -> [f64; 3] {
        if self.even_n == 0 || self.n == self.even_n {
            return [0.0; 3];
        }
        let (ne, no, n) = (self.even_w, self.w - self.even_w, self.w);
        std::array::from_fn(|c| {
            let e = self.even_sum[c] / ne;
            let o = (self.sum[c] - self.even_sum[c]) / no;
            (e - o) * (e - o) * ne * no / (n * n)
        })
    }
}

/// One pixel's samples in a pass of adaptive sampling (`crate::render::adaptive`): samples
/// `first..first + count` of pixel `pixel` (its index, row-major), each weighing `weight`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelRun {
    pub pixel: u32,
    pub first: u32,
    pub count: u32,
    pub weight: f64,
}

/// The relMSE denominator's offset, mean (x − r)² / (r² + 0.01): keeps dark pixels from
/// dominating (pbrt, Mitsuba; `hexray compare`).
pub const RELMSE_EPSILON: f64 = 0.01;

/// A whole image of pixel statistics, row 0 at the top.
///
/// Methods that splat light subpaths into the pixels they are seen in (light tracing, BDPT) make
/// the pixels of one iteration dependent: one light subpath adds to several pixels. Their
/// samples are *batch means*: an iteration, which traces one light subpath per pixel and one
/// camera subpath per pixel, is one independent estimate of the whole image, and each pixel
/// adds its value of that iteration as one sample, so the per-pixel statistics stay right. The
/// image mean's standard error cannot then be summed over pixels; it comes from the scatter of
/// the iterations' own image means, which such methods record in `iteration_means`.
#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<PixelStats>,
    /// The image mean of each iteration, one sample per iteration, where pixels share samples
    /// (`Some` for light tracing and BDPT; `None` where pixels are independent).
    pub iteration_means: Option<PixelStats>,
    /// The sampler that drew the samples (`--sampler`): it decides how their error is
    /// estimated ([`Film::var_of_mean`]), and the renderers draw the film's samples with it.
    pub sampler: SamplerKind,
}

impl Film {
    pub fn new(width: u32, height: u32) -> Film {
        Film {
            width,
            height,
            pixels: vec![PixelStats::default(); (width * height) as usize],
            iteration_means: None,
            sampler: SamplerKind::Independent,
        }
    }

    /// This film, drawn with `sampler`.
    pub fn with_sampler(self, sampler: SamplerKind) -> Film {
        Film { sampler, ..self }
    }

    /// The estimated variance of the mean of `p`, a pixel of this film or its iteration
    /// means: from the samples' own scatter where they are independent
    /// ([`PixelStats::var_of_mean`]), from the two independent streams' means where they are
    /// Sobol points, whose scatter within a stream understates nothing but measures nothing
    /// either ([`PixelStats::var_of_mean_from_streams`]).
    pub fn var_of_mean(&self, p: &PixelStats) -> [f64; 3] {
        match self.sampler {
            SamplerKind::Independent => p.var_of_mean(),
            SamplerKind::Sobol => p.var_of_mean_from_streams(),
        }
    }

    /// A film for a method whose pixels share samples within an iteration (see the type).
    pub fn with_iteration_means(width: u32, height: u32) -> Film {
        Film {
            iteration_means: Some(PixelStats::default()),
            ..Film::new(width, height)
        }
    }

    /// Samples per pixel taken so far (accumulated + dropped): the same for every pixel but
    /// under adaptive sampling, where this is their mean, rounded ([`Film::mean_spp`]).
    pub fn spp(&self) -> u64 {
        self.mean_spp().round() as u64
    }

    /// Samples per pixel taken so far, on average over the pixels.
    pub fn mean_spp(&self) -> f64 {
        let total: u64 = self.pixels.iter().map(|p| p.n + p.dropped).sum();
        total as f64 / self.pixels.len().max(1) as f64
    }

    pub fn dropped(&self) -> u64 {
        self.pixels.iter().map(|p| p.dropped).sum()
    }

    /// Per-pixel means as f32 RGB, for outputs.
    pub fn mean_image(&self) -> Vec<[f32; 3]> {
        self.pixels
            .iter()
            .map(|p| p.mean().map(|x| x as f32))
            .collect()
    }

    /// Per-pixel variance of the mean as f32 RGB, for outputs.
    pub fn variance_image(&self) -> Vec<[f32; 3]> {
        self.pixels
            .iter()
            .map(|p| self.var_of_mean(p).map(|x| x as f32))
            .collect()
    }

    /// The relMSE this film's image is expected to have against the exact image, from its own
    /// noise: the mean over pixel-channels of var / (m² + 0.01), with m a pixel's mean and var
    /// the estimated variance of that mean ([`Film::var_of_mean`]), what
    /// `hexray compare` measures against a reference, E (x − r)² = var + bias². Each pixel's
    /// samples are independent (a path-traced sample, or an iteration, whose streams are its
    /// own), so its variance is right even where an iteration's pixels share light subpaths. A
    /// method's bias is not in it (merging, Whitted). None before two samples.
    pub fn estimated_relmse(&self) -> Option<f64> {
        if self.pixels.first().is_none_or(|p| p.n < 2) {
            return None;
        }
        let mut sum = 0.0;
        for p in &self.pixels {
            let (m, v) = (p.mean(), self.var_of_mean(p));
            for c in 0..3 {
                sum += v[c] / (m[c] * m[c] + RELMSE_EPSILON);
            }
        }
        Some(sum / (3 * self.pixels.len()) as f64)
    }

    /// The mean over all pixels, and its standard error. Where pixels are independent
    /// estimates, the variance of their average is the sum of their variances over N²; where
    /// they share samples (`iteration_means`), it is the variance of the mean of the
    /// iterations' image means (batch means).
    pub fn image_mean(&self) -> ([f64; 3], [f64; 3]) {
        let n = self.pixels.len() as f64;
        let mut m = [0.0; 3];
        let mut v = [0.0; 3];
        for p in &self.pixels {
            let (pm, pv) = (p.mean(), self.var_of_mean(p));
            for c in 0..3 {
                m[c] += pm[c];
                v[c] += pv[c];
            }
        }
        let se = match &self.iteration_means {
            Some(batches) => self.var_of_mean(batches).map(f64::sqrt),
            None => v.map(|x| x.sqrt() / n),
        };
        (m.map(|x| x / n), se)
    }
}

/// Refuses to add samples of `method` to a film that holds another kind: a film of a splatting
/// method keeps the iterations' image means (batch means) and one of path tracing does not.
pub fn check_film_for(method: crate::transport::method::Method, film: &Film) -> anyhow::Result<()> {
    if film.spp() > 0 && film.iteration_means.is_some() != method.splats() {
        anyhow::bail!(
            "this film holds samples of another kind of method than {method}; render into a new film"
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variance_of_mean_is_the_unbiased_estimate() {
        let mut p = PixelStats::default();
        for x in [1.0f32, 2.0, 3.0, 4.0] {
            p.add(Vec3::splat(x));
        }
        // Sample variance of 1..4 is 5/3; of the mean of 4 samples, 5/12.
        assert!((p.var_of_mean()[0] - 5.0 / 12.0).abs() < 1e-12);
        assert_eq!(p.mean()[1], 2.5);
    }

    #[test]
    fn non_finite_samples_are_counted_and_dropped() {
        let mut p = PixelStats::default();
        p.add(Vec3::ONE);
        p.add(Vec3::new(f32::NAN, 0.0, 0.0));
        p.add(Vec3::new(0.0, f32::INFINITY, 0.0));
        assert_eq!((p.n, p.dropped), (1, 2));
        assert_eq!(p.mean(), [1.0; 3]);
    }

    /// Weighted batches: the mean is Σcx / Σc, and the variance estimate is unbiased for
    /// samples of one variance (checked here on exact sums: two batches of constant values
    /// have the plain formula's variance once the weights are equal).
    #[test]
    fn weighted_batches_give_the_weighted_mean_and_the_plain_variance_at_equal_weights() {
        let batch = |xs: &[f32]| {
            let mut b = PixelStats::default();
            for &x in xs {
                b.add(Vec3::splat(x));
            }
            b
        };
        let mut p = PixelStats::default();
        p.merge_weighted(&batch(&[1.0, 3.0]), 2.0);
        p.merge_weighted(&batch(&[5.0, 7.0, 9.0, 11.0]), 0.5);
        // (2 (1 + 3) + 0.5 (5 + 7 + 9 + 11)) / (2 · 2 + 0.5 · 4) = 24 / 6.
        assert!((p.mean()[0] - 4.0).abs() < 1e-12);
        let mut q = PixelStats::default();
        q.merge_weighted(&batch(&[1.0, 2.0]), 3.0);
        q.merge_weighted(&batch(&[3.0, 4.0]), 3.0);
        assert!((q.var_of_mean()[0] - 5.0 / 12.0).abs() < 1e-12);
        assert!((q.mean()[0] - 2.5).abs() < 1e-12);
    }
}
