//! `hexray compare` computes what it says on inputs whose answers are known in closed form, reads
//! .npy and EXR alike, and refuses images of different sizes.

use crate::common::repo;
use crate::common::temp_dir;
use hexray::analysis::compare::{compare, read_image, RELMSE_EPSILON};
use hexray::film::output::{write_exr, Metadata, RgbImage};
use npyz::WriterBuilder;
use std::path::Path;
use std::process::Command;

/// A deterministic test image with values spread over [0, 2).
fn image(w: usize, h: usize) -> RgbImage {
    RgbImage {
        width: w,
        height: h,
        pixels: (0..w * h)
            .map(|i| {
                let x = i as f32;
                [
                    (x * 0.37).fract() * 2.0,
                    (x * 0.61).fract(),
                    (x * 0.13).fract() * 0.5,
                ]
            })
            .collect(),
    }
}

fn write_npy(path: &Path, img: &RgbImage) {
    let data: Vec<f32> = img.pixels.iter().flatten().copied().collect();
    let mut out = npyz::WriteOptions::new()
        .default_dtype()
        .shape(&[img.height as u64, img.width as u64, 3])
        .writer(std::fs::File::create(path).unwrap())
        .begin_nd()
        .unwrap();
    out.extend(data).unwrap();
    out.finish().unwrap();
}

#[test]
fn identical_images_have_zero_error_and_ratio_one() {
    let a = image(16, 8);
    let c = compare(&a, &a, Some((&a, &a))).unwrap();
    assert_eq!(c.rmse, 0.0);
    assert_eq!(c.relmse, 0.0);
    assert_eq!(c.ratio, [1.0; 3]);
    assert_eq!(c.beyond_5_se, Some(0.0));
    assert_eq!(c.mean_z2, Some(0.0));
}

/// x = r + k everywhere: RMSE = k exactly, relMSE = mean k² / (r² + 0.01), and with every
/// variance of the mean equal to v, z² = k² / 2v, beyond 5 s.e. iff k² / 2v > 25.
#[test]
fn a_constant_offset_gives_the_closed_form_errors() {
    let r = image(16, 8);
    let k = 0.125f32; // exact in binary, so x − r = k exactly in f32
    let x = RgbImage {
        pixels: r.pixels.iter().map(|p| p.map(|v| v + k)).collect(),
        ..r.clone()
    };
    let var = |v: f32| RgbImage {
        pixels: vec![[v; 3]; r.pixels.len()],
        ..r.clone()
    };
    let c = compare(&x, &r, Some((&var(1e-4), &var(1e-4)))).unwrap();
    let k = k as f64;
    assert!((c.rmse - k).abs() < 1e-12, "RMSE {}", c.rmse);
    let n = 3.0 * r.pixels.len() as f64;
    let relmse: f64 = r
        .pixels
        .iter()
        .flatten()
        .map(|&v| k * k / ((v as f64).powi(2) + RELMSE_EPSILON))
        .sum::<f64>()
        / n;
    assert!(
        (c.relmse - relmse).abs() < 1e-12 * relmse,
        "relMSE {} vs {relmse}",
        c.relmse
    );
    let z2 = k * k / (2.0 * 1e-4f32 as f64);
    assert!((c.mean_z2.unwrap() - z2).abs() < 1e-9 * z2);
    assert_eq!(c.beyond_5_se, Some(1.0)); // z² = 78 > 25 everywhere
}

#[test]
fn an_npy_and_an_exr_of_the_same_data_compare_equal() {
    let dir = temp_dir!("npy");
    let a = image(12, 7);
    let (npy, exr) = (dir.join("a.npy"), dir.join("a.exr"));
    write_npy(&npy, &a);
    write_exr(&exr, &a, &Metadata::default()).unwrap();
    let (from_npy, from_exr) = (read_image(&npy).unwrap(), read_image(&exr).unwrap());
    assert_eq!(from_npy, a);
    let c = compare(&from_npy, &from_exr, None).unwrap();
    assert_eq!((c.rmse, c.ratio), (0.0, [1.0; 3]));
    // And through the CLI, machine-readable.
    let o = Command::new(crate::common::hexray_bin())
        .args(["compare", "--json"])
        .arg(&npy)
        .arg(&exr)
        .output()
        .unwrap();
    assert!(o.status.success());
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["rmse"], 0.0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn images_of_different_sizes_are_a_clear_error() {
    let dir = temp_dir!("size");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    write_exr(&a, &image(16, 8), &Metadata::default()).unwrap();
    write_exr(&b, &image(8, 16), &Metadata::default()).unwrap();
    let o = Command::new(crate::common::hexray_bin())
        .current_dir(repo("."))
        .arg("compare")
        .arg(&a)
        .arg(&b)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("16x8") && stderr.contains("8x16"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Each reference pixel repeated 2x2: every block's mean is the reference pixel.
fn upsampled(img: &RgbImage, k: usize) -> RgbImage {
    RgbImage {
        width: img.width * k,
        height: img.height * k,
        pixels: (0..img.width * img.height * k * k)
            .map(|i| {
                let (x, y) = (i % (img.width * k), i / (img.width * k));
                img.pixels[(y / k) * img.width + x / k]
            })
            .collect(),
    }
}

/// A render at twice the reference's size is compared as its 2x2 block means (a box-filtered
/// pixel is the mean of its sub-pixels): the reference repeated 2x2 has zero error, and one
/// sub-pixel raised by 4 moves its block's mean by exactly 1.
#[test]
fn a_render_at_twice_the_size_compares_as_its_block_means() {
    let dir = temp_dir!("blocks");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    let reference = image(8, 6);
    let mut big = upsampled(&reference, 2);
    write_exr(&b, &reference, &Metadata::default()).unwrap();
    let run = |a: &Path, big: &RgbImage| {
        write_exr(a, big, &Metadata::default()).unwrap();
        let o = Command::new(crate::common::hexray_bin())
            .current_dir(repo("."))
            .args(["compare", "--json"])
            .arg(a)
            .arg(&b)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()
    };
    let same = run(&a, &big);
    assert_eq!(same["rmse"].as_f64(), Some(0.0), "{same}");
    assert_eq!(same["width"].as_u64(), Some(8));
    big.pixels[0][0] += 4.0;
    let raised = run(&a, &big);
    let expected = (1.0f64 / (3.0 * 48.0)).sqrt();
    let rmse = raised["rmse"].as_f64().unwrap();
    assert!((rmse - expected).abs() < 1e-6 * expected, "{raised}");
    std::fs::remove_dir_all(&dir).unwrap();
}
