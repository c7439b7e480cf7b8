//! The statistics that tests and tools share: block means with their standard errors, Welch's
//! t-test with a Bonferroni correction, z-scores against a reference with its own variance, and
//! Pearson's chi-square goodness of fit.

use statrs::function::beta::beta_reg;
use statrs::function::gamma::gamma_ur;

/// Per-pixel means and variances of the mean (the squared standard errors), with the number of
/// samples behind each pixel's mean (for degrees of freedom).
#[derive(Clone, Debug)]
pub struct MeanImage {
    pub width: usize,
    pub height: usize,
    pub mean: Vec<[f64; 3]>,
    pub var: Vec<[f64; 3]>,
    /// Samples per pixel (for Welch's degrees of freedom); `f64::INFINITY` when unknown.
    pub n: f64,
    /// The image mean's standard error where pixels share samples (light tracing, BDPT: the
    /// batch means of `Film::image_mean`); None where pixels are independent estimates.
    pub mean_se: Option<[f64; 3]>,
}

impl MeanImage {
    pub fn from_film(film: &crate::film::Film) -> MeanImage {
        MeanImage {
            width: film.width as usize,
            height: film.height as usize,
            mean: film.pixels.iter().map(|p| p.mean()).collect(),
            var: film.pixels.iter().map(|p| film.var_of_mean(p)).collect(),
            n: film.spp() as f64,
            mean_se: film.iteration_means.as_ref().map(|_| film.image_mean().1),
        }
    }

    /// Averages over `b` x `b` blocks: the block mean is the mean of its pixel means, and its
    /// variance is the sum of the pixel variances over the squared pixel count (pixels are
    /// independent estimates). A partial block at the right or bottom edge is left out.
    pub fn blocks(&self, b: usize) -> MeanImage {
        let (bw, bh) = (self.width / b, self.height / b);
        let k = (b * b) as f64;
        let mut mean = vec![[0.0; 3]; bw * bh];
        let mut var = vec![[0.0; 3]; bw * bh];
        for by in 0..bh {
            for bx in 0..bw {
                let o = by * bw + bx;
                for y in by * b..(by + 1) * b {
                    for x in bx * b..(bx + 1) * b {
                        let i = y * self.width + x;
                        for c in 0..3 {
                            mean[o][c] += self.mean[i][c] / k;
                            var[o][c] += self.var[i][c] / (k * k);
                        }
                    }
                }
            }
        }
        MeanImage {
            width: bw,
            height: bh,
            mean,
            var,
            n: self.n * k,
            mean_se: None,
        }
    }

    /// The mean of all pixels per channel, and its standard error (from the batch means where
    /// pixels share samples).
    pub fn grand_mean(&self) -> ([f64; 3], [f64; 3]) {
        let k = self.mean.len() as f64;
        let mut m = [0.0; 3];
        let mut v = [0.0; 3];
        for (pm, pv) in self.mean.iter().zip(&self.var) {
            for c in 0..3 {
                m[c] += pm[c] / k;
                v[c] += pv[c] / (k * k);
            }
        }
        (m, self.mean_se.unwrap_or(v.map(f64::sqrt)))
    }
}

/// Two-sided p-value of Student's t with `df` degrees of freedom:
/// P(|T| >= |t|) = I_{df / (df + t²)}(df / 2, 1 / 2).
pub fn student_t_two_sided_p(t: f64, df: f64) -> f64 {
    if !t.is_finite() {
        return 0.0;
    }
    if !df.is_finite() || df > 1e7 {
        return normal_two_sided_p(t);
    }
    beta_reg(df / 2.0, 0.5, df / (df + t * t))
}

/// Two-sided p-value of a standard normal: P(|Z| >= |z|) = erfc(|z| / sqrt 2).
pub fn normal_two_sided_p(z: f64) -> f64 {
    statrs::function::erf::erfc(z.abs() / std::f64::consts::SQRT_2)
}

/// Upper tail of the chi-square distribution with `dof` degrees of freedom: Q(dof/2, x/2).
pub fn chi_square_upper_p(x: f64, dof: f64) -> f64 {
    if x <= 0.0 || dof <= 0.0 {
        return 1.0;
    }
    gamma_ur(dof / 2.0, x / 2.0)
}

/// The outcome of comparing two images block by block and channel by channel.
#[derive(Clone, Debug)]
pub struct WelchReport {
    /// Tests whose p-value fell below the Bonferroni threshold alpha / tests.
    pub rejected: usize,
    pub tests: usize,
    pub smallest_p: f64,
    /// The largest |t| seen, for messages.
    pub largest_t: f64,
    pub threshold: f64,
}

impl WelchReport {
    /// True when no block differs: the two images are statistically the same at level alpha.
    pub fn same(&self) -> bool {
        self.rejected == 0
    }
}

/// Welch's unequal-variance t-test for every block and channel of two block-mean images, with
/// Welch–Satterthwaite degrees of freedom, and a Bonferroni correction so that the whole family
/// of tests has false-rejection probability at most `alpha`. Channels whose both variances are
/// zero (a black region) are compared exactly.
pub fn welch_blocks(a: &MeanImage, b: &MeanImage, alpha: f64) -> WelchReport {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let tests = a.mean.len() * 3;
    let threshold = alpha / tests as f64;
    let (mut rejected, mut smallest_p, mut largest_t) = (0, 1.0f64, 0.0f64);
    let (dfa, dfb) = (a.n - 1.0, b.n - 1.0);
    for i in 0..a.mean.len() {
        for c in 0..3 {
            let (va, vb) = (a.var[i][c], b.var[i][c]);
            let diff = a.mean[i][c] - b.mean[i][c];
            let p = if va + vb == 0.0 {
                if diff == 0.0 {
                    1.0
                } else {
                    0.0
                }
            } else {
                let t = diff / (va + vb).sqrt();
                largest_t = largest_t.max(t.abs());
                let df = (va + vb).powi(2) / (va * va / dfa + vb * vb / dfb);
                student_t_two_sided_p(t, df)
            };
            smallest_p = smallest_p.min(p);
            if p < threshold {
                rejected += 1;
            }
        }
    }
    WelchReport {
        rejected,
        tests,
        smallest_p,
        largest_t,
        threshold,
    }
}

/// z-scores of a candidate against a reference, each with its own variance of the mean:
/// z = (x − r) / sqrt(var_x + var_r).
#[derive(Clone, Debug)]
pub struct ZReport {
    /// Fraction of pixel-channels with |z| > 5.
    pub beyond_5: f64,
    /// Mean of z² (1 for a correct candidate with correct variances).
    pub mean_z2: f64,
    pub count: usize,
}

pub fn z_scores(x: &MeanImage, r: &MeanImage) -> ZReport {
    assert_eq!((x.width, x.height), (r.width, r.height));
    let (mut beyond, mut z2, mut count) = (0usize, 0.0f64, 0usize);
    for i in 0..x.mean.len() {
        for c in 0..3 {
            let v = x.var[i][c] + r.var[i][c];
            let d = x.mean[i][c] - r.mean[i][c];
            if v <= 0.0 {
                if d != 0.0 {
                    beyond += 1;
                }
                count += 1;
                continue;
            }
            let z = d / v.sqrt();
            z2 += z * z;
            if z.abs() > 5.0 {
                beyond += 1;
            }
            count += 1;
        }
    }
    ZReport {
        beyond_5: beyond as f64 / count as f64,
        mean_z2: z2 / count as f64,
        count,
    }
}

/// Pearson's chi-square test of observed counts against expected counts, pooling cells whose
/// expected count is below 5 into one (pbrt's recipe; the chi-square approximation needs
/// expected counts of at least about 5). Returns (statistic, degrees of freedom, p-value).
pub fn chi_square_test(observed: &[f64], expected: &[f64]) -> (f64, usize, f64) {
    let (mut stat, mut cells) = (0.0, 0usize);
    let (mut pooled_o, mut pooled_e) = (0.0, 0.0);
    for (&o, &e) in observed.iter().zip(expected) {
        if e < 5.0 {
            pooled_o += o;
            pooled_e += e;
        } else {
            stat += (o - e) * (o - e) / e;
            cells += 1;
        }
    }
    if pooled_e > 0.0 {
        stat += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
        cells += 1;
    }
    let dof = cells.saturating_sub(1);
    (stat, dof, chi_square_upper_p(stat, dof as f64))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_p_values_match_tables() {
        // t = 2.228 at 10 dof is the two-sided 5% point; 1.96 for the normal.
        assert!((student_t_two_sided_p(2.228, 10.0) - 0.05).abs() < 1e-3);
        assert!((normal_two_sided_p(1.959_964) - 0.05).abs() < 1e-6);
        // Chi-square with 10 dof: 18.307 is the upper 5% point.
        assert!((chi_square_upper_p(18.307, 10.0) - 0.05).abs() < 1e-4);
    }

    #[test]
    fn chi_square_pools_small_cells() {
        let (stat, dof, p) = chi_square_test(&[10.0, 10.0, 1.0, 2.0], &[10.0, 10.0, 2.0, 1.0]);
        assert_eq!(dof, 2);
        assert_eq!(stat, 0.0);
        assert!((p - 1.0).abs() < 1e-12);
    }
}
