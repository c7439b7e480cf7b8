//! Helpers shared by the integration tests: load a scene, render it on either backend
//! ([`render::Render`], [`on_each_backend!`]), and state statistical expectations.
#![allow(dead_code)]

pub mod parity;
pub mod reference;
pub mod render;

pub(crate) use render::on_each_backend;
pub use render::{Backend, Render};

use hexray::film::Film;
use hexray::layout::FlatScene;
use hexray::scene::Scene;
use std::path::{Path, PathBuf};

/// A path under the repository root: the one the tests were built in, or, when the test binary
/// runs on another machine (built here, run beside a GPU), the working directory, which must
/// then be a copy of the repository.
pub fn repo(rel: &str) -> PathBuf {
    let built_in = Path::new(env!("CARGO_MANIFEST_DIR"));
    if built_in.join("Cargo.toml").exists() {
        built_in.join(rel)
    } else {
        PathBuf::from(rel)
    }
}

/// The `hexray` binary the command-line tests run: this build's, or the one named by
/// `HEXRAY_UNDER_TEST`, so the same tests can be run against an older build to show which of
/// them fail there (`tests/against_build.sh`).
pub fn hexray_bin() -> PathBuf {
    std::env::var_os("HEXRAY_UNDER_TEST")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_hexray")))
}

/// The `hexray` binary, run in the repository root.
pub fn hexray_command() -> std::process::Command {
    let mut c = std::process::Command::new(hexray_bin());
    c.current_dir(repo("."));
    c
}

/// `hexray render SCENE --method METHOD` on the CPU at 16x16 and 2 samples per pixel, with
/// `extra` options, written to `out`: the small render whose summary line and metadata the
/// tests of a method's command line read.
pub fn small_cli_render(
    scene: &str,
    method: &str,
    extra: &[&str],
    out: &Path,
) -> std::process::Output {
    hexray_command()
        .args(["render", scene, "--method", method, "--backend", "cpu"])
        .args(["--width", "16", "--height", "16", "--spp", "2"])
        .args(extra)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

/// An empty folder of this test process for `tag` (emptied if a run left it).
pub fn empty_temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("hexray-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `temp_dir!(name)`: an empty folder for one test's files, named after the calling test file
/// (its module) and `name`, so that no two files' tests share one.
macro_rules! temp_dir {
    ($name:expr) => {
        $crate::common::empty_temp_dir(&format!(
            "{}-{}",
            module_path!().rsplit("::").next().unwrap(),
            $name
        ))
    };
}
pub(crate) use temp_dir;

pub fn load(rel: &str) -> (Scene, FlatScene) {
    let scene = Scene::load(&repo(rel)).unwrap_or_else(|e| panic!("{e}"));
    let flat = FlatScene::build(&scene, hexray::render::CpuBackend::TRAVERSAL);
    (scene, flat)
}

/// z-score of each channel of the image mean against an exact value: (mean − truth) / s.e.
pub fn image_mean_z(film: &Film, truth: [f64; 3]) -> ([f64; 3], [f64; 3], [f64; 3]) {
    let (mean, se) = film.image_mean();
    let z = [0, 1, 2].map(|c| (mean[c] - truth[c]) / se[c]);
    (mean, se, z)
}

/// Asserts that the image mean equals `truth` within 4 standard errors in every channel. For a
/// correct renderer |z| > 4 has probability 6e-5 per channel (normal tails; the image mean of
/// thousands of independent pixel estimates is normal to a good approximation).
pub fn assert_mean_within_4_se(film: &Film, truth: [f64; 3], what: &str) {
    let (mean, se, z) = image_mean_z(film, truth);
    for c in 0..3 {
        assert!(
            z[c].abs() <= 4.0,
            "{what}: channel {c} mean {:.6} vs exact {:.6}: z = {:.2} (s.e. {:.2e})",
            mean[c],
            truth[c],
            z[c],
            se[c]
        );
    }
    eprintln!(
        "{what}: mean {:.5} {:.5} {:.5}, exact {:.5} {:.5} {:.5}, z {:.2} {:.2} {:.2}",
        mean[0], mean[1], mean[2], truth[0], truth[1], truth[2], z[0], z[1], z[2]
    );
}

/// The GPU for tests, shared by all tests of a binary: None (with the reason printed) when no
/// adapter exists, unless `CI` is set, where a missing adapter is a failure (CI installs
/// lavapipe, so GPU tests must run there).
pub fn gpu() -> Option<&'static hexray::gpu::Gpu> {
    use std::sync::OnceLock;
    static GPU: OnceLock<Result<hexray::gpu::Gpu, String>> = OnceLock::new();
    match GPU.get_or_init(|| hexray::gpu::acquire(None).map_err(|e| e.to_string())) {
        Ok(g) => Some(g),
        Err(e) if std::env::var_os("CI").is_some() => panic!("CI is set but {e}"),
        Err(e) => {
            eprintln!("skipping GPU test: {e}");
            None
        }
    }
}

/// Loads a scene file and applies `change` to its description (move the camera, change a
/// material, remove a triangle) before validating it again, for tests that need a variant of a
/// committed scene.
pub fn load_changed(rel: &str, change: impl FnOnce(&mut hexray::scene::SceneDesc)) -> Scene {
    let mut scene = Scene::load(&repo(rel)).unwrap_or_else(|e| panic!("{e}"));
    change(&mut scene.desc);
    if let Err(issue) = hexray::scene::validate::validate(&scene.desc) {
        panic!("{rel} as changed: {}: {}", issue.path, issue.message);
    }
    scene
}

/// Pixels (x, y) with any non-zero sample: radiance is never negative, so a pixel whose sum is 0
/// in every channel took only zero samples.
pub fn lit_pixels(film: &Film) -> Vec<(u32, u32)> {
    (0..film.height)
        .flat_map(|y| (0..film.width).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let p = &film.pixels[(y * film.width + x) as usize];
            p.sum.iter().any(|&s| s != 0.0)
        })
        .collect()
}

/// A rendered image against an exact expected image, pixel groups (blocks, rows) at a time.
#[derive(Clone, Debug)]
pub struct TruthReport {
    /// Image mean, its standard error, the exact image mean and the z-score, per channel.
    pub mean: [f64; 3],
    pub se: [f64; 3],
    pub exact: [f64; 3],
    pub z: [f64; 3],
    /// Group-channels whose exact value is positive, each tested by z = (mean − exact) / s.e.
    pub tested: usize,
    /// Those whose two-sided normal p-value is below the Bonferroni threshold alpha / tested.
    pub rejected: usize,
    /// The largest |z| among the tested group-channels, with its group and channel.
    pub worst: (f64, usize, usize),
    /// Group-channels whose exact value is 0 but which took a non-zero sample.
    pub light_where_black: usize,
    pub dropped: u64,
}

impl TruthReport {
    /// The image agrees with the exact one: no group beyond the Bonferroni threshold, the image
    /// mean within 4 s.e. per channel, no light where there can be none, no non-finite sample.
    pub fn agrees(&self) -> bool {
        self.rejected == 0
            && self.z.iter().all(|z| z.abs() <= 4.0)
            && self.light_where_black == 0
            && self.dropped == 0
    }

    /// Prints the report and asserts that the image agrees with the exact one.
    pub fn assert_agrees(&self, what: &str) {
        eprintln!("{what}: {}", self.summary());
        assert!(self.agrees(), "{what}: {}", self.summary());
    }

    /// Prints the report and asserts that a planted error that darkens the image was caught:
    /// the image disagrees, with every channel's mean more than 4 s.e. below the exact one.
    pub fn assert_rejected_as_too_dark(&self, what: &str) {
        eprintln!("{what}: {}", self.summary());
        assert!(
            !self.agrees() && self.z.iter().all(|z| *z < -4.0),
            "{what} went unnoticed: {}",
            self.summary()
        );
    }

    pub fn summary(&self) -> String {
        format!(
            "image mean {:.5} {:.5} {:.5} ± {:.1e} {:.1e} {:.1e}, exact {:.5} {:.5} {:.5}, \
             z {:.2} {:.2} {:.2}; {} of {} group-channels rejected (worst z {:.2}, group {} \
             channel {}); {} lit where exactly black; {} dropped",
            self.mean[0],
            self.mean[1],
            self.mean[2],
            self.se[0],
            self.se[1],
            self.se[2],
            self.exact[0],
            self.exact[1],
            self.exact[2],
            self.z[0],
            self.z[1],
            self.z[2],
            self.rejected,
            self.tested,
            self.worst.0,
            self.worst.1,
            self.worst.2,
            self.light_where_black,
            self.dropped
        )
    }
}

/// z = (mean − exact) / s.e., with a zero s.e. (a constant estimate) giving 0 when the mean is
/// exact and an infinite z otherwise.
fn z_of(mean: f64, exact: f64, var: f64) -> f64 {
    if var > 0.0 {
        (mean - exact) / var.sqrt()
    } else if mean == exact {
        0.0
    } else {
        (mean - exact) * f64::INFINITY
    }
}

/// Compares a film with exact per-pixel expectations `exact` (row-major, per channel) over the
/// pixel groups that `group` assigns (None: the pixel is in no group): each group's mean is the
/// mean of its pixel means, its variance the sum of their variances over the squared count
/// (pixels are independent estimates; for light tracing and BDPT, whose light subpaths splat
/// into several pixels, nearly so: tests/standard_error.rs measures how nearly). Group-channels with a positive exact value are tested
/// with Bonferroni's correction at family level `alpha`; those with exact value 0 must have
/// taken only zero samples. The image mean is compared too.
pub fn against_truth(
    film: &Film,
    exact: &[[f64; 3]],
    group: impl Fn(u32, u32) -> Option<usize>,
    alpha: f64,
) -> TruthReport {
    use hexray::analysis::stats::normal_two_sided_p;
    assert_eq!(exact.len(), film.pixels.len());
    // Per group: the sums of the pixel means, variances and exact values, and the pixel count.
    #[derive(Clone, Default)]
    struct Group {
        mean: [f64; 3],
        var: [f64; 3],
        exact: [f64; 3],
        pixels: f64,
    }
    let mut groups: Vec<Group> = Vec::new();
    let (mut mean, mut var, mut ex) = ([0.0; 3], [0.0; 3], [0.0; 3]);
    let n = film.pixels.len() as f64;
    for y in 0..film.height {
        for x in 0..film.width {
            let i = (y * film.width + x) as usize;
            let (pm, pv) = (film.pixels[i].mean(), film.pixels[i].var_of_mean());
            for c in 0..3 {
                mean[c] += pm[c] / n;
                var[c] += pv[c] / (n * n);
                ex[c] += exact[i][c] / n;
            }
            if let Some(g) = group(x, y) {
                if g >= groups.len() {
                    groups.resize(g + 1, Group::default());
                }
                let e = &mut groups[g];
                for c in 0..3 {
                    e.mean[c] += pm[c];
                    e.var[c] += pv[c];
                    e.exact[c] += exact[i][c];
                }
                e.pixels += 1.0;
            }
        }
    }
    let tested = groups
        .iter()
        .map(|g| (0..3).filter(|&c| g.exact[c] > 0.0).count())
        .sum::<usize>();
    let (mut rejected, mut light_where_black, mut worst) = (0, 0, (0.0f64, 0, 0));
    for (gi, g) in groups.iter().enumerate() {
        if g.pixels == 0.0 {
            continue;
        }
        let k = g.pixels;
        for c in 0..3 {
            let (m, v, e) = (g.mean[c] / k, g.var[c] / (k * k), g.exact[c] / k);
            if e == 0.0 {
                if m != 0.0 {
                    light_where_black += 1;
                }
                continue;
            }
            let z = z_of(m, e, v);
            if z.abs() > worst.0.abs() || z.is_nan() {
                worst = (z, gi, c);
            }
            // A NaN z (a NaN mean) is rejected too.
            let p = normal_two_sided_p(z);
            if p.is_nan() || p < alpha / tested as f64 {
                rejected += 1;
            }
        }
    }
    // Where pixels share samples (light tracing, BDPT), the image mean's variance is that of
    // the iterations' batch means, not a sum over pixels.
    if film.iteration_means.is_some() {
        var = film.image_mean().1.map(|s| s * s);
    }
    TruthReport {
        mean,
        se: var.map(f64::sqrt),
        exact: ex,
        z: [0, 1, 2].map(|c| z_of(mean[c], ex[c], var[c])),
        tested,
        rejected,
        worst,
        light_where_black,
        dropped: film.dropped(),
    }
}

/// Per pixel, the mean over channels of (a − b)²/(b² + 0.01): the terms relMSE averages (the
/// second film as the reference).
pub fn relmse_terms(a: &Film, b: &Film) -> Vec<f64> {
    use hexray::analysis::stats::MeanImage;
    let (a, b) = (MeanImage::from_film(a), MeanImage::from_film(b));
    a.mean
        .iter()
        .zip(&b.mean)
        .map(|(x, r)| {
            (0..3)
                .map(|c| (x[c] - r[c]).powi(2) / (r[c] * r[c] + 0.01))
                .sum::<f64>()
                / 3.0
        })
        .collect()
}

/// relMSE of one film against another of the same size (the second as the reference).
pub fn relmse_between(a: &Film, b: &Film) -> f64 {
    let terms = relmse_terms(a, b);
    terms.iter().sum::<f64>() / terms.len() as f64
}

/// How two films of the same size differ pixel by pixel, by [`relmse_terms`]. Returns the
/// number of pixels whose term exceeds `tol` or is NaN, and the largest term (NaN if any is). Two renders of the same
/// streams that differ only in f32 arithmetic have small terms (1e-16 to 1e-9 measured); a
/// flipped discrete decision (Russian roulette, a photon on the merge radius) moves a few pixels
/// by a whole path's contribution.
pub fn pixels_differing(a: &Film, b: &Film, tol: f64) -> (usize, f64) {
    let mut count = 0;
    let mut worst = 0.0f64;
    for term in relmse_terms(a, b) {
        if term > tol || term.is_nan() {
            count += 1;
        }
        if !worst.is_nan() && (term > worst || term.is_nan()) {
            worst = term;
        }
    }
    (count, worst)
}

/// The default merge radius of `method` for a square image of the scene at `rel`
/// (`MergeRadius::default_for`; the view's reach depends on the image's aspect, not its size).
pub fn default_radius(
    rel: &str,
    method: hexray::transport::method::Method,
) -> hexray::transport::merging::MergeRadius {
    let (scene, flat) = load(rel);
    let camera = hexray::transport::camera::Camera::new(&scene.desc.camera, 1, 1);
    hexray::transport::merging::MergeRadius::default_for(&flat, &camera, method)
}
