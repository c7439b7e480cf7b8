//! Merging renders of one scene made with different seeds ("parts") into one: the work of a
//! frame split by samples, not tiles, so the result is unbiased and seamless whatever machine
//! rendered which part.
//!
//! Each part carries per pixel its mean m_i over n_i samples and the variance of that mean v_i
//! (`NAME_var.exr`, from Σx² as in `crate::film`). The sums are recovered exactly in f64,
//! Σx = n_i m_i and Σx² = n_i (n_i − 1) v_i + n_i m_i², added over parts, and the merged mean
//! and variance of the mean follow from the totals by the film's own formulas: the merge is
//! the render that took all the parts' samples. The parts are summed in seed order, so the file
//! is bit-identical for any order of the arguments.
//!
//! n_i is the part's spp. A pixel that dropped non-finite samples has fewer; the file does not
//! say which pixels, so such a part (`dropped_samples` > 0, which the tests' scenes never
//! produce) is merged with a warning in its metadata rather than refused.

use crate::film::output::{read_exr, Metadata, RgbImage};
use std::fmt;
use std::path::{Path, PathBuf};

/// Why parts cannot be merged: every message names the file.
#[derive(Debug)]
pub struct MergeError(pub String);

impl fmt::Display for MergeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for MergeError {}

/// One part: its mean and variance-of-mean images and its metadata.
#[derive(Clone, Debug)]
pub struct Part {
    pub path: PathBuf,
    pub mean: RgbImage,
    pub var: RgbImage,
    pub meta: Metadata,
    pub spp: u64,
    pub seed: u32,
}

/// `NAME_var.exr` beside `NAME.exr`.
pub fn variance_path(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!("{stem}_var.exr"))
}

/// Reads a part and its variance file, checking that it is a hexray render.
pub fn load_part(path: &Path) -> Result<Part, MergeError> {
    if path
        .file_stem()
        .is_some_and(|s| s.to_string_lossy().ends_with("_var"))
    {
        return Err(MergeError(format!(
            "{}: a variance file, not a part; give the parts' mean EXRs (their _var.exr are \
             found beside them)",
            path.display()
        )));
    }
    let (mean, meta) =
        read_exr(path).map_err(|e| MergeError(format!("{}: {e:#}", path.display())))?;
    let field = |key: &str| {
        meta.get(key).map(str::to_string).ok_or_else(|| {
            MergeError(format!(
                "{}: not a hexray render (no `{key}` in its `hexray` attribute); merge only files \
                 written by `hexray render`",
                path.display()
            ))
        })
    };
    let spp: u64 = field("spp")?.parse().map_err(|_| {
        MergeError(format!(
            "{}: the spp in its metadata is not a number",
            path.display()
        ))
    })?;
    let seed: u32 = field("seed")?.parse().map_err(|_| {
        MergeError(format!(
            "{}: the seed in its metadata is not a number",
            path.display()
        ))
    })?;
    field("scene_sha1")?;
    let var_path = variance_path(path);
    if !var_path.exists() {
        return Err(MergeError(format!(
            "{}: its variance file {} is missing; render parts with --variance",
            path.display(),
            var_path.display()
        )));
    }
    let (var, _) =
        read_exr(&var_path).map_err(|e| MergeError(format!("{}: {e:#}", var_path.display())))?;
    if (var.width, var.height) != (mean.width, mean.height) {
        return Err(MergeError(format!(
            "{}: {}x{} but its variance file is {}x{}",
            path.display(),
            mean.width,
            mean.height,
            var.width,
            var.height
        )));
    }
    if spp < 2 {
        return Err(MergeError(format!(
            "{}: {spp} spp carries no variance; render parts with at least 2 spp",
            path.display()
        )));
    }
    if spp > u64::from(u32::MAX) {
        return Err(MergeError(format!(
            "{}: spp {spp} is more than a render takes (at most {}); the file's metadata is \
             damaged",
            path.display(),
            u32::MAX
        )));
    }
    // The variance file must be the one written with this image (a stale NAME_var.exr from
    // an earlier render under the same name would pair another render's variance with it).
    let var_meta = crate::film::output::read_exr_metadata(&var_path)
        .map_err(|e| MergeError(format!("{}: {e:#}", var_path.display())))?;
    for key in ["spp", "seed", "scene_sha1", "method"] {
        if var_meta.get(key) != meta.get(key) {
            return Err(MergeError(format!(
                "{}: its variance file {} is from another render ({key} {} against {}); \
                 render the part again with --variance",
                path.display(),
                var_path.display(),
                var_meta.get(key).unwrap_or("missing"),
                meta.get(key).unwrap_or("missing")
            )));
        }
    }
    check_pixels(path, &mean, false)?;
    check_pixels(&var_path, &var, true)?;
    Ok(Part {
        path: path.to_path_buf(),
        mean,
        var,
        meta,
        spp,
        seed,
    })
}

/// Refuses an image with a pixel that is not finite, or (a variance) negative, by file and
/// pixel: either would poison the merged sums silently.
fn check_pixels(path: &Path, image: &RgbImage, variance: bool) -> Result<(), MergeError> {
    let bad = |v: &f32| !v.is_finite() || (variance && *v < 0.0);
    if let Some(i) = image.pixels.iter().position(|p| p.iter().any(bad)) {
        let what = if variance {
            "a negative or non-finite variance"
        } else {
            "a non-finite value"
        };
        return Err(MergeError(format!(
            "{}: pixel ({}, {}) holds {what} {:?}; hexray never writes one, so the file is \
             damaged",
            path.display(),
            i % image.width,
            i / image.width,
            image.pixels[i]
        )));
    }
    Ok(())
}

/// The merged render.
#[derive(Clone, Debug)]
pub struct Merged {
    pub mean: RgbImage,
    pub var: RgbImage,
    pub meta: Metadata,
}

/// Checks that the parts belong together (same scene, method, sampler and size, distinct seeds)
/// and merges
/// them; the argument order does not matter.
pub fn merge(mut parts: Vec<Part>) -> Result<Merged, MergeError> {
    parts.sort_by_key(|p| p.seed);
    let Some(first) = parts.first() else {
        return Err(MergeError(
            "nothing to merge: give at least one part".into(),
        ));
    };
    let (sha, w, h) = (
        first.meta.get("scene_sha1").unwrap_or_default().to_string(),
        first.mean.width,
        first.mean.height,
    );
    for p in &parts {
        if p.meta.get("scene_sha1") != Some(sha.as_str()) {
            return Err(MergeError(format!(
                "{}: a render of another scene ({} with sha1 {}) than {} ({} with sha1 {sha}); \
                 merge only parts of one scene file",
                p.path.display(),
                p.meta.get("scene").unwrap_or("?"),
                p.meta.get("scene_sha1").unwrap_or("?"),
                first.path.display(),
                first.meta.get("scene").unwrap_or("?"),
            )));
        }
        // An adaptive render's pixels have counts of their own, which the EXR does not hold.
        if p.meta.get("adaptive") == Some("true") {
            return Err(MergeError(format!(
                "{}: rendered with --adaptive, whose pixels each took their own number of \
                 samples; merge only parts rendered without it",
                p.path.display()
            )));
        }
        // Files written before `--method` existed are path-traced.
        let method_of = |p: &Part| p.meta.get("method").unwrap_or("path").to_string();
        if method_of(p) != method_of(first) {
            return Err(MergeError(format!(
                "{}: rendered with --method {}, but {} with --method {}; merge only parts of one \
                 method (their estimators and statistics differ)",
                p.path.display(),
                method_of(p),
                first.path.display(),
                method_of(first)
            )));
        }
        // Files written before `--sampler` existed drew independent numbers.
        let sampler_of = |p: &Part| p.meta.get("sampler").unwrap_or("independent").to_string();
        if sampler_of(p) != sampler_of(first) {
            return Err(MergeError(format!(
                "{}: rendered with --sampler {}, but {} with --sampler {}; merge only parts of \
                 one sampler (the merged file names one)",
                p.path.display(),
                sampler_of(p),
                first.path.display(),
                sampler_of(first)
            )));
        }
        if (p.mean.width, p.mean.height) != (w, h) {
            return Err(MergeError(format!(
                "{}: {}x{} pixels, but {} is {w}x{h}; render every part at one resolution",
                p.path.display(),
                p.mean.width,
                p.mean.height,
                first.path.display()
            )));
        }
    }
    for pair in parts.windows(2) {
        if pair[0].seed == pair[1].seed {
            return Err(MergeError(format!(
                "{} and {} both have seed {}: they hold the same samples, and merging them would \
                 count those twice; give each part its own --seed",
                pair[0].path.display(),
                pair[1].path.display(),
                pair[0].seed
            )));
        }
    }

    // Recover Σx and Σx² per pixel and channel, and add them over the parts in seed order.
    let pixels = w * h;
    let mut sum = vec![[0.0f64; 3]; pixels];
    let mut sum_sq = vec![[0.0f64; 3]; pixels];
    let mut total: u64 = 0;
    for p in &parts {
        let n = p.spp as f64;
        for i in 0..pixels {
            for c in 0..3 {
                let m = p.mean.pixels[i][c] as f64;
                let v = p.var.pixels[i][c] as f64;
                sum[i][c] += n * m;
                sum_sq[i][c] += n * (n - 1.0) * v + n * m * m;
            }
        }
        total = total.checked_add(p.spp).ok_or_else(|| {
            MergeError(format!(
                "{}: the parts' samples add up to more than 2^64",
                p.path.display()
            ))
        })?;
    }
    let n = total as f64;
    let mut mean = Vec::with_capacity(pixels);
    let mut var = Vec::with_capacity(pixels);
    for i in 0..pixels {
        mean.push(sum[i].map(|s| (s / n) as f32));
        var.push(std::array::from_fn(|c| {
            let ss = sum_sq[i][c] - sum[i][c] * sum[i][c] / n;
            (ss.max(0.0) / (n * (n - 1.0))) as f32
        }));
    }

    let mut meta = Metadata::default();
    for key in [
        "scene",
        "scene_name",
        "scene_sha1",
        "hexray_version",
        "width",
        "height",
        "method",
        "sampler",
    ] {
        if let Some(v) = first.meta.get(key) {
            meta.set(key, v);
        }
    }
    let join = |f: &dyn Fn(&Part) -> String| parts.iter().map(f).collect::<Vec<_>>().join(",");
    let distinct = |key: &str| {
        let set: std::collections::BTreeSet<&str> = parts
            .iter()
            .map(|p| p.meta.get(key).unwrap_or("?"))
            .collect();
        set.into_iter().collect::<Vec<_>>().join(",")
    };
    let sum_field = |key: &str| -> f64 {
        parts
            .iter()
            .filter_map(|p| p.meta.get(key)?.parse::<f64>().ok())
            .sum()
    };
    meta.set("spp", total);
    meta.set("parts", parts.len());
    meta.set("seeds", join(&|p| p.seed.to_string()));
    meta.set("backend", distinct("backend"));
    meta.set("device", distinct("device"));
    meta.set(
        "render_seconds",
        format!("{:.6}", sum_field("render_seconds")),
    );
    let dropped = sum_field("dropped_samples");
    meta.set("dropped_samples", dropped);
    if dropped > 0.0 {
        meta.set(
            "warning",
            "parts dropped non-finite samples; their pixels are weighted by spp, slightly off",
        );
    }
    meta.set(
        "merged_from",
        join(&|p| {
            p.path
                .file_name()
                .map_or(String::new(), |f| f.to_string_lossy().into_owned())
        }),
    );
    Ok(Merged {
        mean: RgbImage {
            width: w,
            height: h,
            pixels: mean,
        },
        var: RgbImage {
            width: w,
            height: h,
            pixels: var,
        },
        meta,
    })
}
