//! Error against time: one progressive render per backend, measured against a reference after
//! every wave of samples (1, 2, 4, 8, ... spp in total), so that speed and accuracy land on one
//! chart. The clock counts render passes only: the kernel's compilation and a first warm-up
//! pass are timed apart (and reported), and computing the error is not render time.

use crate::analysis::compare::{compare, Comparison};
use crate::film::output::RgbImage;
use crate::film::Film;
use crate::math::sampling::SamplerKind;
use crate::render::Backend;
use anyhow::{bail, Context, Result};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// One wave's measurement.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Point {
    pub scene: String,
    /// The series name: "hexray cpu", "hexray gpu", or an overlaid renderer's variant.
    pub backend: String,
    pub device: String,
    pub spp: u32,
    pub seconds: f64,
    pub rmse: f64,
    pub relmse: f64,
}

/// Runs waves of doubling spp on `backend`, drawing with `sampler`, until `budget` seconds of
/// render time are spent (the wave that crosses it finishes; a wave predicted to end past twice
/// the budget is not started), calling `on_point` after each.
#[allow(clippy::too_many_arguments)]
pub fn measure(
    scene: &str,
    backend: &mut dyn Backend,
    sampler: SamplerKind,
    width: u32,
    height: u32,
    reference: &RgbImage,
    budget: f64,
    mut on_point: impl FnMut(&Point),
) -> Result<(Vec<Point>, f64)> {
    if (reference.width, reference.height) != (width as usize, height as usize) {
        bail!(
            "the reference is {}x{} but the curve renders {width}x{height}; give --width and \
             --height of the reference",
            reference.width,
            reference.height
        );
    }
    // Warm-up: a driver may compile the kernel at its first dispatch. Samples of another film.
    let warm = Instant::now();
    backend.pass(0, 1, &mut Film::new(width, height))?;
    let warmup = warm.elapsed().as_secs_f64();

    let mut film = Film::new(width, height).with_sampler(sampler);
    let (mut points, mut elapsed, mut done, mut last_wave) = (Vec::new(), 0.0, 0u32, 0.0);
    let mut target = 1u32;
    while elapsed < budget && elapsed + 2.0 * last_wave <= 2.0 * budget {
        let start = Instant::now();
        backend.pass(done, target - done, &mut film)?;
        last_wave = start.elapsed().as_secs_f64();
        elapsed += last_wave;
        done = target;
        let image = RgbImage {
            width: width as usize,
            height: height as usize,
            pixels: film.mean_image(),
        };
        let c: Comparison = compare(&image, reference, None)?;
        let p = Point {
            scene: scene.to_string(),
            backend: format!("hexray {}", backend.name()),
            device: backend.device(),
            spp: done,
            seconds: elapsed,
            rmse: c.rmse,
            relmse: c.relmse,
        };
        on_point(&p);
        points.push(p);
        target = target.saturating_mul(2);
    }
    Ok((points, warmup))
}

/// Reads another renderer's curve: CSV rows `scene,variant,spp,seconds,rmse,relmse` (the format
/// of `shared/references/mitsuba_curve.csv`), keeping the rows of `scene`; each variant becomes
/// a series named "<renderer> <variant>".
pub fn read_overlay(path: &Path, scene: &str, renderer: &str) -> Result<Vec<Point>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut lines = text.lines().enumerate();
    let header = lines.next().map(|(_, l)| l.trim()).unwrap_or_default();
    let cols: Vec<&str> = header.split(',').collect();
    let col = |name: &str| {
        cols.iter().position(|c| *c == name).with_context(|| {
            format!(
                "{}:1: no `{name}` column; expected scene,variant,spp,seconds,rmse,relmse",
                path.display()
            )
        })
    };
    let (cs, cv, cn, ct, ce, cr) = (
        col("scene")?,
        col("variant")?,
        col("spp")?,
        col("seconds")?,
        col("rmse")?,
        col("relmse")?,
    );
    let mut out = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let num = |c: usize| -> Result<f64> {
            f.get(c).and_then(|v| v.parse().ok()).with_context(|| {
                format!(
                    "{}:{}: column {} is not a number",
                    path.display(),
                    i + 1,
                    c + 1
                )
            })
        };
        if f.get(cs) != Some(&scene) {
            continue;
        }
        out.push(Point {
            scene: scene.to_string(),
            backend: format!("{renderer} {}", f.get(cv).unwrap_or(&"?")),
            device: String::new(),
            spp: num(cn)? as u32,
            seconds: num(ct)?,
            rmse: num(ce)?,
            relmse: num(cr)?,
        });
    }
    Ok(out)
}

/// The points as CSV (`scene,backend,device,spp,seconds,rmse,relmse`; text fields quoted).
pub fn csv(points: &[Point]) -> String {
    let mut s = String::from("scene,backend,device,spp,seconds,rmse,relmse\n");
    for p in points {
        let quote = |t: &str| format!("\"{}\"", t.replace('"', "'"));
        s += &format!(
            "{},{},{},{},{:.6},{:.6e},{:.6e}\n",
            quote(&p.scene),
            quote(&p.backend),
            quote(&p.device),
            p.spp,
            p.seconds,
            p.rmse,
            p.relmse
        );
    }
    s
}

/// relMSE at `seconds` along a series, interpolated log-log between its waves; None outside it.
pub fn relmse_at(points: &[Point], seconds: f64) -> Option<f64> {
    points.windows(2).find_map(|w| {
        let (a, b) = (&w[0], &w[1]);
        (a.seconds <= seconds && seconds <= b.seconds).then(|| {
            let s = (seconds.ln() - a.seconds.ln()) / (b.seconds.ln() - a.seconds.ln());
            (a.relmse.ln() + s * (b.relmse.ln() - a.relmse.ln())).exp()
        })
    })
}

/// Spearman's rank correlation of two equally long samples (no ties expected).
pub fn spearman(x: &[f64], y: &[f64]) -> f64 {
    fn ranks(v: &[f64]) -> Vec<f64> {
        let mut idx: Vec<usize> = (0..v.len()).collect();
        idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
        let mut r = vec![0.0; v.len()];
        for (rank, &i) in idx.iter().enumerate() {
            r[i] = rank as f64;
        }
        r
    }
    let (rx, ry) = (ranks(x), ranks(y));
    let n = x.len() as f64;
    let d2: f64 = rx.iter().zip(&ry).map(|(a, b)| (a - b).powi(2)).sum();
    1.0 - 6.0 * d2 / (n * (n * n - 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(seconds: f64, relmse: f64) -> Point {
        Point {
            scene: "s".into(),
            backend: "b".into(),
            device: String::new(),
            spp: 1,
            seconds,
            rmse: 0.0,
            relmse,
        }
    }

    #[test]
    fn relmse_interpolates_log_log() {
        // relMSE ∝ 1/t is a straight line in log-log: halfway in log t is the geometric mean.
        let s = [pt(1.0, 1e-2), pt(4.0, 2.5e-3)];
        assert!((relmse_at(&s, 2.0).unwrap() - 5e-3).abs() < 1e-12);
        assert_eq!(relmse_at(&s, 8.0), None);
    }

    #[test]
    fn spearman_is_minus_one_for_a_falling_sequence() {
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(spearman(&x, &[5.0, 4.0, 3.0, 2.0, 1.0]), -1.0);
        assert_eq!(spearman(&x, &x), 1.0);
    }
}
