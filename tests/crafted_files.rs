//! Files that `compare`, `merge` and `--resume` read are checked before they are trusted: a
//! header that claims more pixels than its file holds is refused before any
//! allocation, and merge refuses, by file and pixel, what would poison its sums silently.

use crate::common::temp_dir;
use hexray::film::output::{read_exr, write_exr, RgbImage};
use std::path::{Path, PathBuf};
use std::process::Output;

fn hexray(args: &[&str]) -> Output {
    crate::common::hexray_command().args(args).output().unwrap()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A 16x16 path-traced render of `scene` into `out` (with its variance when `variance`).
fn render(scene: &str, seed: u32, spp: u32, variance: bool, out: &Path) {
    let (seed, spp) = (seed.to_string(), spp.to_string());
    let mut args = vec![
        "render",
        scene,
        "--backend",
        "cpu",
        "--method",
        "path",
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        &spp,
        "-q",
        "--seed",
        &seed,
        "--out",
        s(out),
    ];
    if variance {
        args.push("--variance");
    }
    let o = hexray(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A part of cornell_box at 16x16, 4 spp, with its variance.
fn part(dir: &Path, name: &str, seed: u32) -> PathBuf {
    let out = dir.join(name);
    render("scenes/cornell_box.json", seed, 4, true, &out);
    out
}

/// Rewrites an EXR's pixels or metadata, as a damaged or crafted file would have them.
fn rewrite(path: &Path, edit: impl FnOnce(&mut RgbImage, &mut hexray::film::output::Metadata)) {
    let (mut image, mut meta) = read_exr(path).unwrap();
    edit(&mut image, &mut meta);
    write_exr(path, &image, &meta).unwrap();
}

fn refused(o: &Output, words: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    // An exit status, not a signal (SIGABRT from a failed allocation has none).
    assert!(
        matches!(o.status.code(), Some(1 | 2)),
        "{:?}: {err}",
        o.status
    );
    assert!(err.contains(words), "expected {words:?} in: {err}");
}

#[test]
fn a_header_claiming_more_pixels_than_the_file_holds_is_refused_before_allocating() {
    let dir = temp_dir!("header");
    let a = part(&dir, "a.exr", 1);
    // Patch the data window (box2i: xmin, ymin, xmax, ymax) to 100000 x 100000.
    let mut bytes = std::fs::read(&a).unwrap();
    let key = b"dataWindow\0box2i\0";
    let at = bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
    for (k, v) in [0i32, 0, 99_999, 99_999].iter().enumerate() {
        bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
    let crafted = dir.join("crafted.exr");
    std::fs::write(&crafted, &bytes).unwrap();
    let o = hexray(&["compare", s(&crafted), s(&a)]);
    refused(&o, "more than a file of");
    let o = hexray(&["merge", s(&crafted), s(&a), "--out", s(&dir.join("m.exr"))]);
    refused(&o, "more than a file of");
}

#[test]
fn merge_refuses_a_non_finite_pixel_by_file_and_position() {
    let dir = temp_dir!("nan");
    let (a, b) = (part(&dir, "a.exr", 1), part(&dir, "b.exr", 2));
    rewrite(&b, |img, _| img.pixels[16 * 3 + 5][1] = f32::NAN);
    let o = hexray(&["merge", s(&a), s(&b), "--out", s(&dir.join("m.exr"))]);
    refused(&o, "pixel (5, 3) holds a non-finite value");
    assert!(!dir.join("m.exr").exists());
}

#[test]
fn merge_refuses_a_negative_variance() {
    let dir = temp_dir!("negvar");
    let (a, b) = (part(&dir, "a.exr", 1), part(&dir, "b.exr", 2));
    rewrite(&dir.join("b_var.exr"), |img, _| img.pixels[7][0] = -1e-3);
    let o = hexray(&["merge", s(&a), s(&b), "--out", s(&dir.join("m.exr"))]);
    refused(&o, "pixel (7, 0) holds a negative or non-finite variance");
}

#[test]
fn merge_refuses_spp_beyond_what_a_render_takes() {
    let dir = temp_dir!("spp");
    let (a, b) = (part(&dir, "a.exr", 1), part(&dir, "b.exr", 2));
    for f in [b.clone(), dir.join("b_var.exr")] {
        rewrite(&f, |_, meta| meta.set("spp", u64::MAX));
    }
    let o = hexray(&["merge", s(&a), s(&b), "--out", s(&dir.join("m.exr"))]);
    refused(&o, "is more than a render takes");
}

#[test]
fn a_stale_variance_file_is_refused_by_merge_and_compare() {
    let dir = temp_dir!("stale");
    let (a, b) = (part(&dir, "a.exr", 1), part(&dir, "b.exr", 2));
    // b rendered again without --variance: its _var.exr is the old render's.
    render("scenes/cornell_box.json", 2, 6, false, &b);
    let o = hexray(&["merge", s(&a), s(&b), "--out", s(&dir.join("m.exr"))]);
    refused(&o, "is from another render (spp 4 against 6)");
    let o = hexray(&["compare", s(&b), s(&a)]);
    refused(&o, "is not the variance of");
}

#[test]
fn compare_thresholds_set_the_exit_status_and_other_scenes_are_flagged() {
    let dir = temp_dir!("thresholds");
    let (a, b) = (part(&dir, "a.exr", 1), part(&dir, "b.exr", 2));
    assert!(hexray(&["compare", s(&a), s(&b), "--max-relmse", "10"])
        .status
        .success());
    let o = hexray(&["compare", s(&a), s(&b), "--max-relmse", "1e-12"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("above --max-relmse"));
    let o = hexray(&["compare", s(&a), s(&b), "--max-px5", "0.5"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // A render of another scene file is named in the report.
    let c = dir.join("c.exr");
    render("scenes/glass_room.json", 1, 4, true, &c);
    let o = hexray(&["compare", s(&c), s(&a)]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("renders of different scene files"));
}
