//! Long renders committed as references (`tests/data/references/stability/`, made by
//! `docs/figures/stability.sh references`), and the statistic that compares a render against one.

use super::repo;
use hexray::analysis::stats::{welch_blocks, MeanImage};
use hexray::film::output::read_exr;
use hexray::film::Film;

/// A reference render: `NAME.exr` (mean) and `NAME_var.exr` (variance of the mean), with the
/// samples per pixel from its metadata.
pub fn read(rel: &str) -> MeanImage {
    let path = repo(rel);
    let (mean, meta) = read_exr(&path).unwrap_or_else(|e| panic!("{e:#}"));
    let var_path = path.with_file_name(format!(
        "{}_var.exr",
        path.file_stem().unwrap().to_string_lossy()
    ));
    let (var, _) = read_exr(&var_path).unwrap_or_else(|e| panic!("{e:#}"));
    let spp: f64 = meta.get("spp").and_then(|s| s.parse().ok()).unwrap();
    MeanImage {
        width: mean.width,
        height: mean.height,
        mean: mean.pixels.iter().map(|p| p.map(f64::from)).collect(),
        var: var.pixels.iter().map(|p| p.map(f64::from)).collect(),
        n: spp,
        mean_se: None,
    }
}

/// [`mean_z`] of a rendered film against the reference file `reference`.
pub fn film_mean_z(what: &str, film: &Film, reference: &str) -> [f64; 3] {
    mean_z(what, &MeanImage::from_film(film), &read(reference))
}

/// Every channel's image mean within 4 combined standard errors of the reference's: for a
/// correct renderer |z| > 4 has probability 6e-5 per channel (the image mean of thousands of
/// independent pixel estimates is normal to a good approximation).
pub fn means_agree(z: [f64; 3]) -> bool {
    z.iter().all(|z| z.abs() <= 4.0)
}

/// How a render's image mean compares with a reference's, per channel: the difference over the
/// combined standard error. The image mean is the same at any resolution (same camera, box
/// filter), so the render may be smaller than the reference.
pub fn mean_z(what: &str, candidate: &MeanImage, reference: &MeanImage) -> [f64; 3] {
    let (m, s) = candidate.grand_mean();
    let (mr, sr) = reference.grand_mean();
    let z = [0, 1, 2].map(|c| (m[c] - mr[c]) / (s[c] * s[c] + sr[c] * sr[c]).sqrt());
    eprintln!(
        "{what}: image mean {:.5} {:.5} {:.5} (s.e. {:.1e}) vs reference {:.5} {:.5} {:.5} \
         (s.e. {:.1e}): z {:.2} {:.2} {:.2}",
        m[0], m[1], m[2], s[0], mr[0], mr[1], mr[2], sr[0], z[0], z[1], z[2]
    );
    z
}

/// How a render compares with a reference of the same scene and size.
#[derive(Debug)]
pub struct Agreement {
    /// Block-channels (8x8 pixel blocks) whose Welch t-test rejects at the Bonferroni level.
    pub rejected_blocks: usize,
    pub tests: usize,
    /// Per channel: (image mean − reference mean) / combined standard error.
    pub mean_z: [f64; 3],
    pub mean: [f64; 3],
    pub se: [f64; 3],
}

impl Agreement {
    /// No block differs at family level α = 0.01 and every channel's image mean is within 4
    /// combined standard errors (6e-5 false-alarm probability per channel).
    pub fn agrees(&self) -> bool {
        self.rejected_blocks == 0 && self.mean_z.iter().all(|z| z.abs() <= 4.0)
    }
}

/// Compares `candidate` with `reference`: per 8x8 block and channel, Welch's t-test with a
/// Bonferroni correction at α = 0.01 overall (as the GPU parity test), and the image means with
/// their combined standard error.
pub fn compare(what: &str, candidate: &MeanImage, reference: &MeanImage) -> Agreement {
    let report = welch_blocks(&candidate.blocks(8), &reference.blocks(8), 0.01);
    let (m, s) = candidate.grand_mean();
    let (mr, sr) = reference.grand_mean();
    let mean_z = [0, 1, 2].map(|c| (m[c] - mr[c]) / (s[c] * s[c] + sr[c] * sr[c]).sqrt());
    eprintln!(
        "{what}: mean {:.5} {:.5} {:.5} (s.e. {:.1e}) vs reference {:.5} {:.5} {:.5} (s.e. {:.1e}): \
         z {:.2} {:.2} {:.2}; {} of {} block-channels rejected (largest |t| {:.2})",
        m[0], m[1], m[2], s[0], mr[0], mr[1], mr[2], sr[0], mean_z[0], mean_z[1], mean_z[2],
        report.rejected, report.tests, report.largest_t
    );
    Agreement {
        rejected_blocks: report.rejected,
        tests: report.tests,
        mean_z,
        mean: m,
        se: s,
    }
}
