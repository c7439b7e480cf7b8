//! A render's film on disk (`NAME.film` beside `NAME.exr`): the f64 sums behind the image and
//! what made them, so that a stopped or finished render can be continued (`--resume`).
//!
//! The EXR holds f32 means, from which the f64 sums cannot be recovered; this file holds them
//! exactly. Since every sample is drawn from counter-based streams indexed by (pixel, sample)
//! and the CPU backend's sums do not depend on how samples are split into passes
//! (tests/determinism.rs), a render resumed from here to N samples is bit for bit the render of
//! N samples in one go. (The GPU backend sums each pass in f32 before folding it into the f64
//! film, so there a resumed render is the same estimator on the same streams, equal to an
//! uninterrupted one within rounding, not bit for bit.)
//!
//! Layout, all little-endian:
//! - the magic `hexray film\n` (12 bytes), a u32 header length, the header as JSON
//!   ([`FilmIdentity`]);
//! - per pixel, row 0 first: sum[3] f64, sum_sq[3] f64, n u64, dropped u64, even_sum[3] f64,
//!   even_n u64, w f64, w_sq f64, even_w f64 (120 bytes; version 2 ends each record before w,
//!   at 96 bytes, and version 1 before even_sum, at 64 bytes);
//! - for the batch-means methods, one more such record: the iterations' image means.
//!
//! The reader checks that the file is exactly as long as its header says before allocating
//! anything, so a crafted header cannot make it ask for more memory than the file holds.

use crate::film::{Film, PixelStats};
use crate::math::sampling::SamplerKind;
use anyhow::{bail, ensure, Context, Result};
use serde::{Deserialize, Serialize};
use std::io::Read;
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 12] = b"hexray film\n";
/// Bytes of one pixel record.
const RECORD: usize = 120;
/// Bytes of one pixel record of version 2, which lacks the weight sums.
const RECORD_V2: usize = 96;
/// Bytes of one pixel record of version 1, which lacks the even-sample sums.
const RECORD_V1: usize = 64;
/// The longest header read (a header is a few hundred bytes).
const MAX_HEADER: u32 = 1 << 16;
/// The largest image side the renderer accepts (`--width`, `--height`).
pub const MAX_SIDE: u32 = 16384;

/// What made a film: enough to continue it with the same scene, streams and estimator, and to
/// tell it from the film of another render.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilmIdentity {
    pub version: u32,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel in the film (accumulated + dropped); under adaptive sampling, pixel
    /// counts differ and this is their mean, rounded down.
    pub spp: u64,
    /// Whether the samples were spent adaptively (`--adaptive`): each pixel has its own count.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub adaptive: bool,
    pub seed: u32,
    /// `--method`, as written on the command line.
    pub method: String,
    pub light_samples: u32,
    /// The merging methods' r_1 (scene units) and alpha, exactly as rendered.
    pub merge_radius: Option<f32>,
    pub merge_alpha: Option<f32>,
    /// The view's reach up to which the merge radius grows with the distance from the camera
    /// (`MergeRadius::reach`; absent where the radius is the same at every vertex).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub merge_reach: Option<f32>,
    /// `--light-paths` as asked for (absent where N took its default, `merging::light_paths`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light_paths: Option<u32>,
    /// Radiosity's `--patch-size` and `--patch-rays` as rendered (absent for other methods).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub patch_size: Option<f32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub patch_rays: Option<u32>,
    /// `--sampler` (absent in films of version 1: independent).
    #[serde(default)]
    pub sampler: SamplerKind,
    /// The scene file as given, and the SHA-1 of its bytes.
    pub scene: String,
    pub scene_sha1: String,
    /// Render time of all sessions so far, in seconds.
    pub render_seconds: f64,
}

impl FilmIdentity {
    /// Version 2 added each record's even-sample sums (`PixelStats::even_sum`, `even_n`),
    /// version 3 the weight sums (`PixelStats::w`, `w_sq`, `even_w`).
    pub const VERSION: u32 = 3;
}

/// `NAME.film` beside `NAME.exr`.
pub fn film_path(exr: &Path) -> PathBuf {
    exr.with_extension("film")
}

fn put_record(out: &mut Vec<u8>, p: &PixelStats) {
    for v in p.sum.iter().chain(&p.sum_sq) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&p.n.to_le_bytes());
    out.extend_from_slice(&p.dropped.to_le_bytes());
    for v in &p.even_sum {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&p.even_n.to_le_bytes());
    for v in [p.w, p.w_sq, p.even_w] {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

fn get_record(b: &[u8]) -> PixelStats {
    let f = |i: usize| f64::from_le_bytes(b[8 * i..8 * i + 8].try_into().unwrap());
    let u = |i: usize| u64::from_le_bytes(b[8 * i..8 * i + 8].try_into().unwrap());
    let (n, even_n) = (u(6), if b.len() >= RECORD_V2 { u(11) } else { 0 });
    // Before version 3 every weight was 1.
    let weights = if b.len() == RECORD {
        [f(12), f(13), f(14)]
    } else {
        [n as f64, n as f64, even_n as f64]
    };
    PixelStats {
        sum: [f(0), f(1), f(2)],
        sum_sq: [f(3), f(4), f(5)],
        n,
        dropped: u(7),
        even_sum: if b.len() >= RECORD_V2 {
            [f(8), f(9), f(10)]
        } else {
            [0.0; 3]
        },
        even_n,
        w: weights[0],
        w_sq: weights[1],
        even_w: weights[2],
    }
}

/// The file's bytes for `film` made as `identity` says.
pub fn encode(film: &Film, identity: &FilmIdentity) -> Vec<u8> {
    let header = serde_json::to_vec(identity).expect("the identity serialises");
    let records = film.pixels.len() + usize::from(film.iteration_means.is_some());
    let mut out = Vec::with_capacity(MAGIC.len() + 4 + header.len() + records * RECORD);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(&header);
    for p in &film.pixels {
        put_record(&mut out, p);
    }
    if let Some(m) = &film.iteration_means {
        put_record(&mut out, m);
    }
    out
}

/// Writes the film atomically (a stopped write leaves the previous file).
pub fn write(path: &Path, film: &Film, identity: &FilmIdentity) -> Result<()> {
    let bytes = encode(film, identity);
    crate::film::output::write_atomically(path, |tmp| {
        std::fs::write(tmp, &bytes).with_context(|| format!("writing {}", tmp.display()))
    })
}

/// Reads and checks a film file: its length against its header before allocating, then every
/// pixel (as many samples as the header says, finite sums, non-negative sums of squares).
pub fn read(path: &Path) -> Result<(Film, FilmIdentity)> {
    let name = path.display();
    let mut file = std::fs::File::open(path).with_context(|| format!("opening {name}"))?;
    let len = file
        .metadata()
        .with_context(|| format!("reading {name}"))?
        .len();
    let mut head = [0u8; 16];
    file.read_exact(&mut head)
        .with_context(|| format!("{name}: too short for a film file"))?;
    ensure!(
        &head[..12] == MAGIC,
        "{name} is not a hexray film file (written beside each render's EXR)"
    );
    let header_len = u32::from_le_bytes(head[12..16].try_into().unwrap());
    ensure!(
        header_len <= MAX_HEADER,
        "{name}: header of {header_len} bytes is implausibly long"
    );
    let mut header = vec![0u8; header_len as usize];
    file.read_exact(&mut header)
        .with_context(|| format!("{name}: the header is cut short"))?;
    let id: FilmIdentity =
        serde_json::from_slice(&header).with_context(|| format!("{name}: unreadable header"))?;
    // Version 1 lacks the even-sample sums, which only the Sobol sampler's error estimate
    // uses; every film of version 1 was drawn by the independent sampler. Versions 1 and 2
    // lack the weight sums: their samples all weigh 1.
    ensure!(
        (1..=FilmIdentity::VERSION).contains(&id.version),
        "{name}: film format version {} (this hexray reads versions 1 to {})",
        id.version,
        FilmIdentity::VERSION
    );
    let record = match id.version {
        1 => RECORD_V1,
        2 => RECORD_V2,
        _ => RECORD,
    };
    ensure!(
        (1..=MAX_SIDE).contains(&id.width) && (1..=MAX_SIDE).contains(&id.height),
        "{name}: image size {}x{} is out of range",
        id.width,
        id.height
    );
    let method = <crate::transport::method::Method as clap::ValueEnum>::from_str(&id.method, true)
        .map_err(|e| anyhow::anyhow!("{name}: method {:?}: {e}", id.method))?;
    // The batch-means methods keep one more record: the iterations' image means.
    let splats = method.splats();
    let pixels = id.width as u64 * id.height as u64;
    let expected = 16 + header_len as u64 + (pixels + u64::from(splats)) * record as u64;
    if len != expected {
        bail!(
            "{name}: {len} bytes, but a {}x{} film of this method is {expected} bytes \
             (cut short, or written for another method)",
            id.width,
            id.height
        );
    }
    let mut body = vec![0u8; (len - 16 - header_len as u64) as usize];
    file.read_exact(&mut body)
        .with_context(|| format!("reading {name}"))?;
    let mut records = body.chunks_exact(record).map(get_record);
    let mut film = Film::new(id.width, id.height).with_sampler(id.sampler);
    for (i, p) in film.pixels.iter_mut().enumerate() {
        *p = records.next().unwrap();
        check_record(p, (!id.adaptive).then_some(id.spp)).with_context(|| {
            format!(
                "{name}: pixel ({}, {})",
                i % id.width as usize,
                i / id.width as usize
            )
        })?;
    }
    if splats {
        let m = records.next().unwrap();
        ensure!(
            m.sum.iter().chain(&m.sum_sq).all(|v| v.is_finite()) && m.n + m.dropped == id.spp,
            "{name}: the iterations' image means do not match the header's {} samples",
            id.spp
        );
        film.iteration_means = Some(m);
    }
    Ok((film, id))
}

/// A pixel's record: `spp` samples where every pixel has as many (not so under adaptive
/// sampling), finite sums, positive weights where there are samples.
fn check_record(p: &PixelStats, spp: Option<u64>) -> Result<()> {
    if let Some(spp) = spp {
        ensure!(
            p.n.checked_add(p.dropped) == Some(spp),
            "{} + {} dropped samples, not the header's {spp}",
            p.n,
            p.dropped
        );
    }
    ensure!(
        p.sum
            .iter()
            .chain(&p.sum_sq)
            .chain(&p.even_sum)
            .chain(&[p.w, p.w_sq, p.even_w])
            .all(|v| v.is_finite()),
        "a sum is not finite"
    );
    ensure!(
        (p.n == 0 || p.w > 0.0 && p.w_sq > 0.0) && p.even_w >= 0.0 && p.even_w <= p.w,
        "weight sums {}, {}, {} do not fit {} samples",
        p.w,
        p.w_sq,
        p.even_w,
        p.n
    );
    ensure!(
        p.even_n <= p.n,
        "{} even-index samples of {} in all",
        p.even_n,
        p.n
    );
    ensure!(
        p.sum_sq.iter().all(|&v| v >= 0.0),
        "a sum of squares is negative"
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn identity(width: u32, height: u32, spp: u64) -> FilmIdentity {
        identity_of("path", width, height, spp)
    }

    fn identity_of(method: &str, width: u32, height: u32, spp: u64) -> FilmIdentity {
        FilmIdentity {
            version: FilmIdentity::VERSION,
            width,
            height,
            spp,
            adaptive: false,
            seed: 7,
            sampler: SamplerKind::Sobol,
            method: method.into(),
            light_samples: 1,
            merge_radius: Some(0.012_345_679),
            merge_alpha: Some(0.75),
            merge_reach: Some(7.5),
            light_paths: Some(1000),
            patch_size: None,
            patch_rays: None,
            scene: "scenes/x.json".into(),
            scene_sha1: "0123".into(),
            render_seconds: 1.5,
        }
    }

    fn film(width: u32, height: u32, spp: u32, splats: bool) -> Film {
        let mut f = if splats {
            Film::with_iteration_means(width, height)
        } else {
            Film::new(width, height)
        };
        for (i, p) in f.pixels.iter_mut().enumerate() {
            for s in 0..spp {
                p.add(Vec3::new(i as f32 * 0.1, s as f32 / 3.0, 1e-7));
            }
        }
        if let Some(m) = &mut f.iteration_means {
            for s in 0..spp {
                m.add(Vec3::splat(s as f32));
            }
        }
        f
    }

    #[test]
    fn films_round_trip_bit_for_bit() {
        let dir = std::env::temp_dir().join(format!("hexray-film-{}", std::process::id()));
        for splats in [false, true] {
            let method = if splats { "vcm" } else { "path" };
            let (f, id) = (film(5, 3, 4, splats), identity_of(method, 5, 3, 4));
            let path = dir.join(format!("a{splats}.film"));
            write(&path, &f, &id).unwrap();
            let (g, id2) = read(&path).unwrap();
            assert_eq!(id, id2);
            assert!(f.pixels == g.pixels && f.iteration_means == g.iteration_means);
            assert_eq!(g.sampler, id.sampler);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Films of versions 1 (records without the even-sample sums, no sampler in the header)
    /// and 2 (without the weight sums) still read: their sums as written, every weight 1,
    /// version 1 drawn by the independent sampler.
    #[test]
    fn films_of_versions_1_and_2_still_read() {
        let dir = std::env::temp_dir().join(format!("hexray-film-old-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (version, record_len) in [(1, RECORD_V1), (2, RECORD_V2)] {
            let path = dir.join(format!("v{version}.film"));
            let f = film(3, 2, 5, false);
            let mut id = serde_json::to_value(identity(3, 2, 5)).unwrap();
            id["version"] = version.into();
            if version == 1 {
                id.as_object_mut().unwrap().remove("sampler");
            }
            let header = serde_json::to_vec(&id).unwrap();
            let mut bytes = MAGIC.to_vec();
            bytes.extend_from_slice(&(header.len() as u32).to_le_bytes());
            bytes.extend_from_slice(&header);
            for p in &f.pixels {
                let mut record = Vec::new();
                put_record(&mut record, p);
                bytes.extend_from_slice(&record[..record_len]);
            }
            std::fs::write(&path, &bytes).unwrap();
            let (g, id) = read(&path).unwrap();
            assert_eq!(id.version, version);
            if version == 1 {
                assert_eq!(g.sampler, SamplerKind::Independent);
            }
            for (a, b) in f.pixels.iter().zip(&g.pixels) {
                assert_eq!(
                    (a.sum, a.sum_sq, a.n, a.dropped, a.w, a.w_sq),
                    (b.sum, b.sum_sq, b.n, b.dropped, b.w, b.w_sq)
                );
                assert_eq!(b.mean(), a.mean());
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_header_larger_than_the_file_is_refused_before_allocating() {
        let dir = std::env::temp_dir().join(format!("hexray-film-big-{}", std::process::id()));
        let path = dir.join("big.film");
        // A 16384 x 16384 header over a 2 x 2 body: refused by length, not by an allocation.
        let mut bytes = encode(&film(2, 2, 1, false), &identity(2, 2, 1));
        let id = serde_json::to_vec(&identity(16384, 16384, 1)).unwrap();
        let old_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        bytes.splice(16..16 + old_len, id.iter().copied());
        bytes[12..16].copy_from_slice(&(id.len() as u32).to_le_bytes());
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(&path, &bytes).unwrap();
        let e = format!("{:#}", read(&path).unwrap_err());
        assert!(e.contains("bytes, but a 16384x16384 film"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_pixel_with_the_wrong_sample_count_is_refused_by_position() {
        let dir = std::env::temp_dir().join(format!("hexray-film-n-{}", std::process::id()));
        let path = dir.join("n.film");
        let mut f = film(3, 2, 2, false);
        f.pixels[4].n = 1;
        write(&path, &f, &identity(3, 2, 2)).unwrap();
        let e = format!("{:#}", read(&path).unwrap_err());
        assert!(e.contains("pixel (1, 1)"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
