//! Comparing a render with a reference, with the metrics Mitsuba and pbrt report: the ratio of
//! image means, RMSE = sqrt(mean (x − r)²), relMSE = mean (x − r)² / (r² + 0.01), and, when
//! both variances of the mean are known, the fraction of pixel-channels beyond 5 standard errors
//! (|x − r| > 5 sqrt(var_x + var_r)) and the mean z². Means over all pixel-channels.

use crate::film::output::{read_exr, read_npy_rgb, RgbImage};
use anyhow::{bail, Result};
use serde::Serialize;
use std::path::Path;

pub use crate::film::RELMSE_EPSILON;

/// What `compare` reports.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Comparison {
    pub width: usize,
    pub height: usize,
    pub candidate_mean: [f64; 3],
    pub reference_mean: [f64; 3],
    /// candidate mean / reference mean, per channel.
    pub ratio: [f64; 3],
    pub rmse: f64,
    pub relmse: f64,
    /// With both variances: the fraction of pixel-channels with |z| > 5.
    pub beyond_5_se: Option<f64>,
    /// With both variances: the mean of z² (1 for a correct pair with correct variances).
    pub mean_z2: Option<f64>,
    /// With the reference's variance: mean var_r / (r² + 0.01), the part of the expected
    /// relMSE that is the reference's own noise (E (x − r)² = var_x + var_r + bias²), to be
    /// subtracted when the reference is not much longer than the candidate.
    pub relmse_reference_noise: Option<f64>,
    /// What the figures do not say: e.g. that an image was rendered by a consistent method
    /// (sppm, vcm) or a biased one (whitted), whose standard error covers its noise but not its
    /// bias.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// The note for an image rendered by a merging method or a biased one (its EXR metadata's
/// `method`), if it was.
pub fn consistency_note(what: &str, path: &Path) -> Option<String> {
    if path
        .extension()
        .is_none_or(|e| !e.eq_ignore_ascii_case("exr"))
    {
        return None;
    }
    let (_, meta) = read_exr(path).ok()?;
    let method = crate::transport::method::Method::from_name(meta.get("method")?)?;
    if let Some(omitted) = method.omits() {
        return Some(format!(
            "the {what} was rendered with {method}, which is biased: it leaves out {omitted}, \
             and its variance (and so the z and 5 s.e. figures) covers its noise only"
        ));
    }
    if method == crate::transport::method::Method::PhotonMap {
        return Some(format!(
            "the {what} was rendered with photon-map, which is biased: its variance (and so the \
             z and 5 s.e. figures) covers its noise, not the bias of its density estimates within \
             radius {}, which more samples do not shrink",
            meta.get("merge_radius").unwrap_or("?"),
        ));
    }
    method.merges().then(|| {
        format!(
            "the {what} was rendered with {method}, which is consistent, not unbiased: its \
             variance (and so the z and 5 s.e. figures) covers its noise, not the bias of \
             merging within radius {} (alpha {}), which shrinks with more iterations",
            meta.get("merge_radius").unwrap_or("?"),
            meta.get("merge_alpha").unwrap_or("?")
        )
    })
}

/// The render metadata of an `.exr` (None for other files or files without it).
fn exr_meta(path: &Path) -> Option<crate::film::output::Metadata> {
    let exr = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    exr.then(|| crate::film::output::read_exr_metadata(path).ok())
        .flatten()
        .filter(|m| m.get("spp").is_some())
}

/// Refuses a variance file written by another render than its image (a stale NAME_var.exr
/// left by an earlier render under the same name): both record the render's identity.
pub fn check_variance_pair(image: &Path, variance: &Path) -> Result<()> {
    let (Some(a), Some(b)) = (exr_meta(image), exr_meta(variance)) else {
        return Ok(());
    };
    for key in ["spp", "seed", "scene_sha1", "method"] {
        if a.get(key) != b.get(key) {
            bail!(
                "{} is not the variance of {} ({key} {} against {}): it is left from another \
                 render; render again with --variance, or give --var/--ref-var",
                variance.display(),
                image.display(),
                b.get(key).unwrap_or("missing"),
                a.get(key).unwrap_or("missing")
            );
        }
    }
    Ok(())
}

/// A note when the candidate and the reference are renders of different scene files.
pub fn scene_note(candidate: &Path, reference: &Path) -> Option<String> {
    let (a, b) = (exr_meta(candidate)?, exr_meta(reference)?);
    let (sa, sb) = (a.get("scene_sha1")?, b.get("scene_sha1")?);
    (sa != sb).then(|| {
        format!(
            "warning: the candidate and the reference are renders of different scene files \
             ({} with sha1 {sa}, {} with sha1 {sb})",
            a.get("scene").unwrap_or("?"),
            b.get("scene").unwrap_or("?")
        )
    })
}

/// Reads an RGB image by extension: `.exr` (linear float) or `.npy` (float32/64, H x W x 3).
pub fn read_image(path: &Path) -> Result<RgbImage> {
    match path.extension().and_then(|e| e.to_str()) {
        Some("exr") => Ok(read_exr(path)?.0),
        Some("npy") => read_npy_rgb(path),
        _ => bail!(
            "{}: unknown image type; give an .exr or a .npy file",
            path.display()
        ),
    }
}

/// The factor k when `candidate` is k times `reference` in both dimensions (k >= 2), so that
/// each k x k block of candidate pixels covers one reference pixel.
pub fn block_factor(candidate: &RgbImage, reference: &RgbImage) -> Option<usize> {
    let (w, h) = (reference.width, reference.height);
    let k = candidate.width.checked_div(w)?;
    (k >= 2 && candidate.width == k * w && candidate.height == k * h).then_some(k)
}

/// Each k x k block's mean: with box-filtered pixels (hexray's, Mitsuba's `box`), the mean of a
/// pixel's k x k sub-pixels is that pixel's value, so a render at k times the reference's size
/// compares with it after this. Applied to a variance of the mean, `variance` divides by k²
/// once more (the mean of k² independent estimates).
pub fn block_mean(image: &RgbImage, k: usize, variance: bool) -> RgbImage {
    let (w, h) = (image.width / k, image.height / k);
    let scale = if variance {
        1.0 / (k * k * k * k) as f64
    } else {
        1.0 / (k * k) as f64
    };
    let mut pixels = vec![[0.0f32; 3]; w * h];
    for (y, row) in pixels.chunks_mut(w).enumerate() {
        for (x, out) in row.iter_mut().enumerate() {
            let mut sum = [0.0f64; 3];
            for dy in 0..k {
                for dx in 0..k {
                    let p = image.pixels[(y * k + dy) * image.width + x * k + dx];
                    for c in 0..3 {
                        sum[c] += p[c] as f64;
                    }
                }
            }
            *out = sum.map(|s| (s * scale) as f32);
        }
    }
    RgbImage {
        width: w,
        height: h,
        pixels,
    }
}

/// The error metrics of a candidate against a reference, computed in f64.
pub fn compare(
    candidate: &RgbImage,
    reference: &RgbImage,
    variances: Option<(&RgbImage, &RgbImage)>,
) -> Result<Comparison> {
    let size = |i: &RgbImage| (i.width, i.height);
    if size(candidate) != size(reference) {
        bail!(
            "the candidate is {}x{} but the reference is {}x{}",
            candidate.width,
            candidate.height,
            reference.width,
            reference.height
        );
    }
    if let Some((vc, vr)) = variances {
        if size(vc) != size(candidate) || size(vr) != size(reference) {
            bail!(
                "a variance image's size ({}x{}, {}x{}) differs from its image's ({}x{})",
                vc.width,
                vc.height,
                vr.width,
                vr.height,
                candidate.width,
                candidate.height
            );
        }
    }
    let n = candidate.pixels.len() as f64;
    let (mut mc, mut mr) = ([0.0f64; 3], [0.0f64; 3]);
    let (mut se, mut rel) = (0.0f64, 0.0f64);
    for (x, r) in candidate.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (x, r) = (x[c] as f64, r[c] as f64);
            mc[c] += x / n;
            mr[c] += r / n;
            se += (x - r).powi(2);
            rel += (x - r).powi(2) / (r * r + RELMSE_EPSILON);
        }
    }
    let (mut beyond, mut z2, mut floor) = (None, None, None);
    if let Some((vc, vr)) = variances {
        let f: f64 = vr
            .pixels
            .iter()
            .zip(&reference.pixels)
            .flat_map(|(v, r)| (0..3).map(move |c| (v[c] as f64, r[c] as f64)))
            .map(|(v, r)| v / (r * r + RELMSE_EPSILON))
            .sum();
        floor = Some(f / (3.0 * n));
        let (mut b, mut z) = (0usize, 0.0f64);
        for i in 0..candidate.pixels.len() {
            for c in 0..3 {
                let d = candidate.pixels[i][c] as f64 - reference.pixels[i][c] as f64;
                let v = vc.pixels[i][c] as f64 + vr.pixels[i][c] as f64;
                let zz = if v > 0.0 {
                    d * d / v
                } else if d == 0.0 {
                    0.0
                } else {
                    f64::INFINITY
                };
                z += zz;
                if zz > 25.0 {
                    b += 1;
                }
            }
        }
        beyond = Some(b as f64 / (3.0 * n));
        z2 = Some(z / (3.0 * n));
    }
    Ok(Comparison {
        width: candidate.width,
        height: candidate.height,
        candidate_mean: mc,
        reference_mean: mr,
        ratio: std::array::from_fn(|c| mc[c] / mr[c]),
        rmse: (se / (3.0 * n)).sqrt(),
        relmse: rel / (3.0 * n),
        beyond_5_se: beyond,
        mean_z2: z2,
        relmse_reference_noise: floor,
        notes: Vec::new(),
    })
}

impl Comparison {
    /// A human-readable report.
    pub fn text(&self) -> String {
        let rgb = |v: [f64; 3]| format!("{:.5} {:.5} {:.5}", v[0], v[1], v[2]);
        let mut s = format!(
            "size           {}x{}\ncandidate mean {}\nreference mean {}\nratio          {}\nRMSE           {:.4e}\nrelMSE         {:.4e}\n",
            self.width,
            self.height,
            rgb(self.candidate_mean),
            rgb(self.reference_mean),
            rgb(self.ratio),
            self.rmse,
            self.relmse
        );
        if let (Some(b), Some(z)) = (self.beyond_5_se, self.mean_z2) {
            s += &format!("beyond 5 s.e.  {:.4} %\nmean z²        {z:.4}\n", 100.0 * b);
        }
        if let Some(f) = self.relmse_reference_noise {
            s += &format!("relMSE of the reference's own noise {f:.4e}\n");
        }
        for note in &self.notes {
            s += &format!("note: {note}\n");
        }
        s
    }
}
