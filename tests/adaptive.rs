//! Adaptive sampling (`--adaptive`, `render::adaptive`): rounds whose per-pixel counts follow
//! the error so far, each sample weighted by its round's budget over its pixel's count.
//!
//! The property that matters is that it leaves the image unbiased: the counts of a round are
//! decided from earlier rounds only, and the weights make each pixel's estimate a fixed-weight
//! mean of unbiased round means. The planted fault pools the same samples with weight 1, so that
//! a pixel's own early samples decide how much they are diluted. Its bias is largest where each
//! pixel decides from its own samples alone (the need not averaged over neighbours, blur 0):
//! there it is 2 % dark, and there the weighted estimate must still be right. With the default
//! box of neighbours the pooled bias shrinks to about 0.3 %, below what these tests resolve.
//!
//! Scene: tncg15_room, whose path-traced error is caustic fireflies (a pixel whose early samples
//! missed the caustic looks converged). Truth: the image mean of the deep references
//! (tests/data/references/README.md, `h100/`), 0.7186 0.6755 0.6265, whose own error is below
//! 1e-4 and which does not depend on the image's resolution.

use crate::common::on_each_backend;
use crate::common::render::{Backend, Render};
use hexray::render::adaptive::AdaptiveSettings;
use hexray::transport::faults::Faults;
use hexray::transport::method::Method;

const TRUTH: [f64; 3] = [0.71858, 0.67550, 0.62654];

/// Each pixel's need from its own samples alone.
const OWN_NEED: AdaptiveSettings = AdaptiveSettings {
    blur: 0.0,
    floor: 0.25,
};

const POOLED: Faults = Faults {
    adaptive_pooled: true,
    ..Faults::NONE
};

/// The image mean of an adaptive render of tncg15_room at `side` x `side` and `spp` samples per
/// pixel on `backend` (seed 1), its standard error, each channel's z against the truth, and the
/// lowest and highest per-pixel sample counts.
fn adaptive_image_mean(
    backend: Backend,
    (side, spp): (u32, u32),
    settings: AdaptiveSettings,
    faults: Faults,
) -> ([f64; 3], [f64; 3], [f64; 3], (u64, u64)) {
    let film = room(side, spp).faults(faults).adaptive(backend, settings);
    let (mean, se) = film.image_mean();
    let counts = film.pixels.iter().map(|p| p.n);
    let (lo, hi) = (counts.clone().min().unwrap(), counts.max().unwrap());
    let z = std::array::from_fn(|c| (mean[c] - TRUTH[c]) / se[c]);
    eprintln!(
        "{backend} {settings:?} {}: mean {mean:.5?}, s.e. {:.1e} {:.1e} {:.1e}, z {z:.2?}, \
         counts {lo}..{hi}",
        if faults == POOLED {
            "pooled (planted)"
        } else {
            "weighted"
        },
        se[0],
        se[1],
        se[2],
    );
    (mean, se, z, (lo, hi))
}

fn room(side: u32, spp: u32) -> Render<'static> {
    Render::file("scenes/tncg15_room.json")
        .method(Method::Path)
        .size(side, side)
        .spp(spp)
        .seed(1)
}

fn assert_within_4_se(z: [f64; 3], what: &str) {
    assert!(z.iter().all(|z| z.abs() <= 4.0), "{what}: z {z:.2?}");
}

on_each_backend! {
    /// Each pixel's counts decided from its own samples alone, the weighted image is right.
    fn the_weighted_image_is_unbiased_where_each_pixel_decides_from_its_own_samples(backend) {
        let (_, _, z, (lo, hi)) = adaptive_image_mean(backend, (256, 16), OWN_NEED, Faults::NONE);
        // The counts did differ: the round spent its budget unevenly.
        assert!(hi >= 3 * lo, "{backend}: counts {lo}..{hi}: nothing adapted");
        assert_within_4_se(z, &format!("{backend}: weighted, own need"));
    }

    /// The planted fault: the same rounds and counts, the samples pooled with weight 1.
    fn pooling_the_samples_is_rejected_as_biased(backend) {
        let (_, _, z, _) = adaptive_image_mean(backend, (256, 16), OWN_NEED, POOLED);
        assert!(z.iter().all(|z| *z < -4.0), "{backend}: pooled: z {z:.2?} not rejected");
    }

    /// The default settings, against the truth and against a uniform render of as many
    /// samples per pixel.
    fn the_default_adaptive_image_equals_the_truth_and_the_uniform_image(backend) {
        let settings = AdaptiveSettings::default();
        let (mean, se, z, (lo, hi)) = adaptive_image_mean(backend, (128, 64), settings, Faults::NONE);
        assert!(hi >= 2 * lo, "{backend}: counts {lo}..{hi}: nothing adapted");
        assert_within_4_se(z, &format!("{backend}: weighted, default settings"));
        let (u, u_se) = room(128, 64).seed(2).on(backend).image_mean();
        let welch: [f64; 3] =
            std::array::from_fn(|c| (mean[c] - u[c]) / (se[c] * se[c] + u_se[c] * u_se[c]).sqrt());
        eprintln!("{backend}: adaptive against uniform: z {welch:.2?}");
        assert_within_4_se(welch, &format!("{backend}: adaptive against uniform"));
    }
}

on_each_backend! {
    /// A stop under way ends the render between passes, or drops the pass under way whole:
    /// the film keeps every sample of the passes before, with their weights, and its image is
    /// as unbiased as a finished one.
    fn a_stopped_adaptive_render_keeps_its_samples(backend) {
        let after = std::time::Duration::from_millis(1500);
        let (film, reason) = room(64, 1 << 20).adaptive_stopped(backend, after);
        assert_eq!(reason, hexray::render::StopReason::Interrupted, "{backend}");
        assert!(film.spp() >= 8, "{backend}: {} spp kept", film.spp());
        let (mean, se) = film.image_mean();
        let z: [f64; 3] = std::array::from_fn(|c| (mean[c] - TRUTH[c]) / se[c]);
        eprintln!("{backend}: stopped at {} spp, z {z:.2?}", film.spp());
        assert_within_4_se(z, &format!("{backend}: stopped"));
    }
}

/// Both backends draw the same samples and plan the same rounds from them: their adaptive
/// films agree pixel by pixel within the GPU's f32 pass sums.
#[test]
fn the_gpu_spends_the_same_samples_as_the_cpu() {
    let Some(_) = crate::common::gpu() else {
        return;
    };
    let render = room(64, 64);
    let settings = AdaptiveSettings::default();
    let (cpu, gpu) = (
        render.adaptive(Backend::Cpu, settings),
        render.adaptive(Backend::Gpu, settings),
    );
    let same_counts = cpu
        .pixels
        .iter()
        .zip(&gpu.pixels)
        .filter(|(a, b)| a.n == b.n)
        .count();
    let (differing, worst) = crate::common::pixels_differing(&cpu, &gpu, 1e-3);
    eprintln!(
        "same counts in {same_counts} of {} pixels; {differing} pixels differ by more than 1e-3 \
         (worst {worst:.1e})",
        cpu.pixels.len()
    );
    assert!(same_counts * 100 >= cpu.pixels.len() * 99, "{same_counts}");
    assert!(differing * 100 <= cpu.pixels.len(), "{differing}");
}

#[test]
fn adaptive_sampling_for_another_method_is_refused_before_any_work() {
    let dir = crate::common::temp_dir!("refused");
    for method in ["vcm", "whitted"] {
        let out = dir.join(format!("{method}.exr"));
        let o = crate::common::small_cli_render(
            "scenes/cornell_box.json",
            method,
            &["--adaptive"],
            &out,
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{method}: {err}");
        assert!(err.contains("--adaptive is for --method path"), "{err}");
        assert!(!out.exists());
    }
}

/// `hexray merge` takes parts of one count per pixel: an adaptive part is refused by name.
#[test]
fn merging_adaptive_parts_is_refused() {
    let dir = crate::common::temp_dir!("merge");
    let parts: Vec<_> = (1..=2)
        .map(|seed| dir.join(format!("p{seed}.exr")))
        .collect();
    for (seed, out) in (1..=2).zip(&parts) {
        let seed = seed.to_string();
        let o = crate::common::small_cli_render(
            "scenes/cornell_box.json",
            "path",
            &["--adaptive", "--variance", "--seed", &seed],
            out,
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let merged = dir.join("merged.exr");
    let o = crate::common::hexray_command()
        .arg("merge")
        .args(&parts)
        .arg("-o")
        .arg(&merged)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("p1.exr: rendered with --adaptive"), "{err}");
    assert!(!merged.exists());
}

/// A resumed adaptive render goes on adaptively from its film, to the mean count asked for.
#[test]
fn an_adaptive_render_resumes_from_its_film() {
    let dir = crate::common::temp_dir!("resume");
    let out = dir.join("a.exr");
    let o = crate::common::hexray_command()
        .args([
            "render",
            "scenes/cornell_box.json",
            "--method",
            "path",
            "--adaptive",
        ])
        .args([
            "--backend",
            "cpu",
            "--width",
            "32",
            "--height",
            "32",
            "--spp",
            "16",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = crate::common::hexray_command()
        .args(["render", "--resume"])
        .arg(&out)
        .args(["--spp", "32"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (film, id) = hexray::film::file::read(&out.with_extension("film")).unwrap();
    assert!(id.adaptive);
    assert_eq!(film.spp(), 32);
    let counts: Vec<u64> = film.pixels.iter().map(|p| p.n).collect();
    assert!(counts.iter().min() < counts.iter().max(), "{counts:?}");
}
