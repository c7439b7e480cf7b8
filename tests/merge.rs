//! Parts rendered with different seeds and merged equal one render with all their samples:
//! same image (statistically), same sample count, same variance; the merge does not depend on
//! the order of its arguments; it refuses what does not belong together; the one-host runner
//! script gives what the CLI gives by hand.

use crate::common::repo;
use crate::common::temp_dir;
use hexray::analysis::stats::{student_t_two_sided_p, welch_blocks, MeanImage};
use hexray::film::output::{read_exr, Metadata, RgbImage};
use std::path::{Path, PathBuf};
use std::process::Command;

const SCENE: &str = "scenes/cornell_box.json";
const SIZE: &str = "48";

fn hexray() -> Command {
    let mut c = Command::new(crate::common::hexray_bin());
    c.current_dir(repo("."));
    c
}

fn render(scene: &str, seed: u32, spp: u32, out: &Path) {
    render_with(scene, seed, spp, "path", out);
}

fn render_with(scene: &str, seed: u32, spp: u32, method: &str, out: &Path) {
    render_args(scene, seed, spp, &["--method", method], out);
}

fn render_args(scene: &str, seed: u32, spp: u32, extra: &[&str], out: &Path) {
    let o = hexray()
        .args([scene, "--backend", "cpu", "--variance", "--quiet"])
        .args(extra)
        .args(["--width", SIZE, "--height", SIZE])
        .args(["--seed", &seed.to_string(), "--spp", &spp.to_string()])
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn merge(parts: &[PathBuf], out: &Path) -> std::process::Output {
    hexray()
        .arg("merge")
        .args(parts)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap()
}

/// The mean EXR, its variance EXR and the metadata, as the statistics want them.
fn load(path: &Path) -> (MeanImage, Metadata) {
    let (mean, meta) = read_exr(path).unwrap();
    let (var, _) = read_exr(&hexray::film::parts::variance_path(path)).unwrap();
    let spp: f64 = meta.get("spp").unwrap().parse().unwrap();
    (mean_image(&mean, &var, spp), meta)
}

fn mean_image(mean: &RgbImage, var: &RgbImage, n: f64) -> MeanImage {
    let widen = |p: &[f32; 3]| p.map(|x| x as f64);
    MeanImage {
        width: mean.width,
        height: mean.height,
        mean: mean.pixels.iter().map(widen).collect(),
        var: var.pixels.iter().map(widen).collect(),
        n,
        mean_se: None,
    }
}

/// Four parts of 64 spp (seeds 1-4), merged, and one independent render of 256 spp (seed 5).
fn four_parts_and_one_render(dir: &Path) -> (PathBuf, PathBuf, Vec<PathBuf>) {
    let parts: Vec<PathBuf> = (1..=4).map(|s| dir.join(format!("part_{s}.exr"))).collect();
    for (s, p) in (1..=4).zip(&parts) {
        render(SCENE, s, 64, p);
    }
    let merged = dir.join("merged.exr");
    let o = merge(&parts, &merged);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let single = dir.join("single.exr");
    render(SCENE, 5, 256, &single);
    (merged, single, parts)
}

/// Per 8x8 block: the log of the ratio of the two images' summed variances of the mean, and a
/// one-sample t-test that its mean over blocks is 0 (blocks are disjoint pixel sets, so their
/// ratios are independent; the t-test takes the ratios' scatter from the data, heavy tails and
/// all). Returns (mean log ratio, t, two-sided p).
fn variance_log_ratio_test(a: &MeanImage, b: &MeanImage) -> (f64, f64, f64) {
    let (ba, bb) = (a.blocks(8), b.blocks(8));
    let logs: Vec<f64> = ba
        .var
        .iter()
        .zip(&bb.var)
        .map(|(va, vb)| (va.iter().sum::<f64>() / vb.iter().sum::<f64>()).ln())
        .collect();
    let k = logs.len() as f64;
    let mean = logs.iter().sum::<f64>() / k;
    let sd = (logs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
    let t = mean / (sd / k.sqrt());
    (mean, t, student_t_two_sided_p(t, k - 1.0))
}

/// Statistics: the block Welch test of `tests/gpu_parity.rs` (8x8 blocks, Bonferroni α = 0.01
/// over blocks x channels) finds no block-channel that differs; the merged file says 256 spp
/// and holds seeds 1-4; and the merged variance of the mean equals the single render's: the
/// block log-ratio t-test (above) does not reject at α = 0.01. Power: the same variance test
/// rejects a merge that averages the parts' variances of the mean instead of combining their
/// sums (4x too large a variance, the classic mistake), and the Welch test rejects a merge in
/// which one part's image is 30 % too bright.
#[test]
fn four_parts_of_64_spp_merged_equal_one_render_of_256() {
    let dir = temp_dir!("equal");
    let (merged, single, parts) = four_parts_and_one_render(&dir);
    let (m, meta) = load(&merged);
    let (s, _) = load(&single);
    assert_eq!(meta.get("spp"), Some("256"));
    assert_eq!(meta.get("seeds"), Some("1,2,3,4"));
    assert_eq!(meta.get("parts"), Some("4"));

    let welch = welch_blocks(&m.blocks(8), &s.blocks(8), 0.01);
    let (log_ratio, t, p) = variance_log_ratio_test(&m, &s);
    eprintln!(
        "merged vs single: {} of {} block-channels rejected (largest |t| {:.2}, smallest p {:.2e}, \
         Bonferroni threshold {:.1e}); variance log ratio {log_ratio:.4} (t {t:.2}, p {p:.3})",
        welch.rejected, welch.tests, welch.largest_t, welch.smallest_p, welch.threshold
    );
    assert_eq!(
        welch.rejected, 0,
        "the merged image differs from the single render"
    );
    assert!(
        p >= 0.01,
        "the merged variance differs from the single render's (p {p:.2e})"
    );

    // Planted error 1: the variances of the parts' means averaged, as if they were the merge's.
    let loaded: Vec<MeanImage> = parts.iter().map(|p| load(p).0).collect();
    let mut naive = m.clone();
    for (i, v) in naive.var.iter_mut().enumerate() {
        *v = std::array::from_fn(|c| loaded.iter().map(|l| l.var[i][c]).sum::<f64>() / 4.0);
    }
    let (_, t_naive, p_naive) = variance_log_ratio_test(&naive, &s);
    eprintln!("planted: averaged variances: t {t_naive:.1}, p {p_naive:.1e}");
    assert!(p_naive < 0.01, "the variance test missed a 4x variance");

    // Planted error 2: one of four parts 30 % too bright (the merge 7.5 % too bright).
    let mut bright = m.clone();
    for (i, px) in bright.mean.iter_mut().enumerate() {
        *px = std::array::from_fn(|c| px[c] + 0.3 * loaded[0].mean[i][c] / 4.0);
    }
    let planted = welch_blocks(&bright.blocks(8), &s.blocks(8), 0.01);
    eprintln!(
        "planted: one part 30 % too bright: {} of {} block-channels rejected",
        planted.rejected, planted.tests
    );
    assert!(
        planted.rejected > 0,
        "the Welch test missed a part 30 % too bright"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Merging is a function of the set of parts: the files written for two argument orders are
/// byte for byte the same (parts are summed in seed order).
#[test]
fn merging_in_any_order_gives_the_same_bytes() {
    let dir = temp_dir!("order");
    let parts: Vec<PathBuf> = (1..=3).map(|s| dir.join(format!("p{s}.exr"))).collect();
    for (s, p) in (1..=3).zip(&parts) {
        render(SCENE, s, 4, p);
    }
    let a = dir.join("a.exr");
    let b = dir.join("b.exr");
    assert!(merge(&parts, &a).status.success());
    let shuffled = vec![parts[2].clone(), parts[0].clone(), parts[1].clone()];
    assert!(merge(&shuffled, &b).status.success());
    for (x, y) in [(&a, &b), (&dir.join("a_var.exr"), &dir.join("b_var.exr"))] {
        assert_eq!(std::fs::read(x).unwrap(), std::fs::read(y).unwrap());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A repeated seed would count the same samples twice: refused, naming both files, exit 2,
/// nothing written.
#[test]
fn a_repeated_seed_is_refused_and_nothing_is_written() {
    let dir = temp_dir!("repeat");
    let (p1, p2) = (dir.join("p1.exr"), dir.join("again.exr"));
    render(SCENE, 7, 4, &p1);
    render(SCENE, 7, 4, &p2);
    let out = dir.join("m.exr");
    let o = merge(&[p1, p2], &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("p1.exr") && stderr.contains("again.exr"),
        "{stderr}"
    );
    assert!(stderr.contains("seed 7"), "{stderr}");
    for f in ["m.exr", "m.png", "m_var.exr"] {
        assert!(!dir.join(f).exists(), "{f} was written");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A part of another scene is refused, naming it, exit 2, nothing written.
#[test]
fn a_part_of_another_scene_is_refused_and_nothing_is_written() {
    let dir = temp_dir!("scene");
    let (p1, p2) = (dir.join("cornell.exr"), dir.join("glass.exr"));
    render(SCENE, 1, 4, &p1);
    render("scenes/glass_room.json", 2, 4, &p2);
    let out = dir.join("m.exr");
    let o = merge(&[p1, p2], &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("glass.exr") && stderr.contains("another scene"),
        "{stderr}"
    );
    for f in ["m.exr", "m.png", "m_var.exr"] {
        assert!(!dir.join(f).exists(), "{f} was written");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_part_of_another_method_is_refused_naming_both() {
    let dir = temp_dir!("method");
    let (p1, p2) = (dir.join("path.exr"), dir.join("bdpt.exr"));
    render(SCENE, 1, 4, &p1);
    render_with(SCENE, 2, 4, "bdpt", &p2);
    let out = dir.join("m.exr");
    let o = merge(&[p1, p2], &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--method bdpt") && stderr.contains("--method path"),
        "{stderr}"
    );
    assert!(!dir.join("m.exr").exists(), "m.exr was written");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_part_of_another_sampler_is_refused_naming_both() {
    let dir = temp_dir!("sampler");
    let (p1, p2) = (dir.join("independent.exr"), dir.join("sobol.exr"));
    render(SCENE, 1, 4, &p1);
    render_args(
        SCENE,
        2,
        4,
        &["--method", "path", "--sampler", "sobol"],
        &p2,
    );
    let out = dir.join("m.exr");
    let o = merge(&[p1, p2], &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--sampler sobol") && stderr.contains("--sampler independent"),
        "{stderr}"
    );
    assert!(!dir.join("m.exr").exists(), "m.exr was written");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sobol_parts_merge_and_keep_their_sampler() {
    let dir = temp_dir!("sobol");
    let parts = [dir.join("a.exr"), dir.join("b.exr")];
    for (seed, p) in [(1, &parts[0]), (2, &parts[1])] {
        render_args(
            SCENE,
            seed,
            4,
            &["--method", "path", "--sampler", "sobol"],
            p,
        );
    }
    let out = dir.join("m.exr");
    let o = merge(&parts, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(read_exr(&out).unwrap().1.get("sampler"), Some("sobol"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Parts of BDPT merge like path tracing's: per pixel, iterations are samples.
#[test]
fn bdpt_parts_merge_and_keep_their_method() {
    let dir = temp_dir!("bdpt");
    let (p1, p2) = (dir.join("a.exr"), dir.join("b.exr"));
    render_with(SCENE, 1, 4, "bdpt", &p1);
    render_with(SCENE, 2, 4, "bdpt", &p2);
    let out = dir.join("m.exr");
    let o = merge(&[p1, p2], &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, meta) = load(&out);
    assert_eq!(meta.get("method"), Some("bdpt"));
    assert_eq!(meta.get("spp"), Some("8"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `deploy/local/render-parts.sh` on 3 parts gives the merged file that rendering seeds 1-3 and
/// merging them by hand gives: the same pixels bit for bit (images do not depend on thread
/// counts or process scheduling) and the same sample count and seeds.
#[test]
fn the_local_runner_script_equals_the_cli_by_hand() {
    let dir = temp_dir!("runner");
    let by_script = dir.join("script");
    let o = Command::new("bash")
        .current_dir(repo("."))
        .arg("deploy/local/render-parts.sh")
        .args([SCENE, "3", "8"])
        .arg(&by_script)
        .args(["--backend", "cpu", "--width", "24", "--height", "24"])
        .env("HEXRAY", crate::common::hexray_bin())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let by_hand = dir.join("hand");
    let parts: Vec<PathBuf> = (1..=3).map(|s| by_hand.join(format!("p{s}.exr"))).collect();
    for (s, p) in (1..=3).zip(&parts) {
        let o = hexray()
            .args([SCENE, "--backend", "cpu", "--variance", "--quiet"])
            .args(["--width", "24", "--height", "24", "--spp", "8"])
            .args(["--seed", &s.to_string(), "--out"])
            .arg(p)
            .output()
            .unwrap();
        assert!(o.status.success());
    }
    let merged = by_hand.join("merged.exr");
    assert!(merge(&parts, &merged).status.success());

    for name in ["merged.exr", "merged_var.exr"] {
        let (a, ma) = read_exr(&by_script.join(name)).unwrap();
        let (b, mb) = read_exr(&by_hand.join(name)).unwrap();
        assert_eq!(a, b, "{name}: pixels differ");
        for key in ["spp", "seeds", "parts", "scene_sha1"] {
            assert_eq!(ma.get(key), mb.get(key), "{name}: {key}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A variance file given as a part, and an output that would overwrite a part, are refused
/// (exit 2) and the part is left as it was.
#[test]
fn a_variance_file_as_a_part_or_an_output_over_a_part_is_refused() {
    let dir = temp_dir!("misuse");
    let (p1, p2) = (dir.join("p1.exr"), dir.join("p2.exr"));
    render(SCENE, 1, 4, &p1);
    render(SCENE, 2, 4, &p2);
    let before = std::fs::read(&p1).unwrap();
    let o = merge(&[p1.clone(), dir.join("p2_var.exr")], &dir.join("m.exr"));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("p2_var.exr") && stderr.contains("variance file"),
        "{stderr}"
    );
    let o = merge(&[p1.clone(), p2], &p1);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("overwrite"), "{stderr}");
    assert_eq!(std::fs::read(&p1).unwrap(), before);
    assert!(!dir.join("m.exr").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
