//! Whitted ray tracing (`--method whitted`, `src/cpu/whitted.rs`, `shaders/whitted.wgsl`) against
//! closed forms of what it computes, direct light and perfect specular transport, and the GPU
//! against the CPU on the same random streams.
//!
//! Planted by hand on 2026-11-28 in `src/cpu/whitted.rs`: √cos θs for cos θs in step 4's direct
//! light, rejected by both direct-light tests (inside the sphere 0.832 for 0.75).

use crate::common::*;
use hexray::film::Film;
use hexray::transport::faults::Faults;
use hexray::transport::method::Method;

/// Whitted's image of the scene at `rel` on `backend`, `size`², `spp` samples, `seed`.
fn whitted(backend: Backend, rel: &str, size: u32, spp: u32, seed: u32, faults: Faults) -> Film {
    Render::file(rel)
        .size(size, size)
        .spp(spp)
        .seed(seed)
        .method(Method::Whitted)
        .faults(faults)
        .on(backend)
}

/// Seeds of the backends' renders, so that the two are independent.
fn seed_of(backend: Backend) -> u32 {
    match backend {
        Backend::Cpu => 11,
        Backend::Gpu => 12,
    }
}

/// The black furnace: a closed cube of walls that emit Le = 1 and reflect nothing, with a mirror
/// sphere and a glass sphere (tint 1) inside (`scenes/furnace/make_furnaces.py`). Every wall the
/// camera sees, straight or in the spheres, has radiance 1, and perfect reflection and
/// refraction lose nothing, so the image is 1 but for the ray trees cut at WHITTED_MAX_DEPTH
/// specular bounces.
const BLACK_FURNACE: &str = "scenes/furnace/black_specular.json";

/// What the cut trees lose in the black furnace, at most: measured 5.1e-4 of the image mean on
/// both backends (32x32, 64 samples, s.e. 1.3e-5), where mirrors and glass that pass on 99 %
/// lose 5.2e-3.
const CUT_TREES: f64 = 1e-3;

/// The black furnace's image mean, with the allowance for cut trees.
fn black_furnace(backend: Backend, faults: Faults) -> ([f64; 3], [f64; 3]) {
    let film = whitted(backend, BLACK_FURNACE, 32, 64, seed_of(backend), faults);
    assert_eq!(film.dropped(), 0, "{backend}: non-finite samples");
    let (mean, se) = film.image_mean();
    eprintln!("{backend} Whitted in the black furnace: mean {mean:?}, s.e. {se:?}");
    (mean, se)
}

fn within_cut_trees(mean: [f64; 3], se: [f64; 3]) -> bool {
    (0..3).all(|c| (mean[c] - 1.0).abs() <= 4.0 * se[c] + CUT_TREES)
}

on_each_backend! {
    /// Direct light under a square emitter is the form factor's (`direct_light.rs`): one
    /// emitter point per diffuse hit, an unbiased estimate of the direct light.
    fn whitted_radiance_under_a_square_emitter_matches_the_form_factor(backend) {
        let film = whitted(backend, crate::direct_light::SCENE, 8, 1024, seed_of(backend), Faults::NONE);
        crate::direct_light::check(&film, &format!("{backend} direct light, Whitted"));
    }

    /// Inside a sphere of radius R that emits Le and reflects with albedo ρ (the merging
    /// furnace, `scenes/furnace/sphere.json`), a wall sees Le from every direction, so Whitted's
    /// radiance is Le + ρ Le (0.75 at ρ = 0.5, where the full solution is 1). And for two points
    /// of a sphere cos θs = cos θl = d / 2R, so cos θs cos θl / d² is 1 / 4R² for every emitter
    /// point: one uniform point gives the direct light exactly, and every sample is 0.75 to f32
    /// rounding.
    fn whitted_inside_an_emitting_sphere_is_emission_plus_one_bounce(backend) {
        let film = whitted(backend, "scenes/furnace/sphere.json", 16, 16, seed_of(backend), Faults::NONE);
        let (mean, _) = film.image_mean();
        assert!(mean.iter().all(|m| (m - 0.75).abs() < 1e-5), "{backend}: mean {mean:?}");
    }

    /// Mirrors and glass of unit reflectance and tint lose nothing: the black furnace's image
    /// is 1.
    fn whitted_mirrors_and_glass_lose_no_light(backend) {
        let (mean, se) = black_furnace(backend, Faults::NONE);
        assert!(within_cut_trees(mean, se), "{backend}: mean {mean:?}, s.e. {se:?}");
    }
}

/// The black furnace has power: mirrors and glass that pass on 99 % are rejected.
#[test]
fn the_black_furnace_rejects_specular_transport_1_percent_too_dark() {
    let dark = Faults {
        specular_scale: 0.99,
        ..Faults::NONE
    };
    let (mean, se) = black_furnace(Backend::Cpu, dark);
    assert!(!within_cut_trees(mean, se), "mean {mean:?}, s.e. {se:?}");
}

/// relMSE of the GPU's Whitted image of tncg15_room against the CPU's on the same streams.
fn same_streams(gpu_faults: Faults) -> Option<f64> {
    gpu()?;
    let render = Render::file("scenes/tncg15_room.json")
        .size(64, 64)
        .spp(16)
        .seed(5)
        .method(Method::Whitted);
    let a = render.cpu();
    let b = render.faults(gpu_faults).gpu();
    let e = relmse_between(&b, &a);
    eprintln!("Whitted, tncg15_room, same seed, GPU against CPU: relMSE {e:.3e}");
    Some(e)
}

/// With the same seed the GPU walks the CPU's ray trees: the images agree to f32 rounding.
#[test]
fn gpu_whitted_equals_cpu_on_the_same_streams() {
    if let Some(e) = same_streams(Faults::NONE) {
        assert!(e < 1e-5, "relMSE {e:e}");
    }
}

/// The same-streams check has power: a GPU whose mirrors and glass pass on 97 % is rejected.
#[test]
fn the_whitted_same_streams_check_rejects_a_gpu_mirror_3_percent_too_dark() {
    let dim = Faults {
        specular_scale: 0.97,
        ..Faults::NONE
    };
    if let Some(e) = same_streams(dim) {
        assert!(e > 1e-5, "relMSE {e:e}");
    }
}

/// A Whitted render says what it leaves out, in its summary line and in its EXR metadata.
#[test]
fn a_whitted_render_says_what_it_leaves_out() {
    let dir = empty_temp_dir("whitted-omits");
    let exr = dir.join("w.exr");
    let o = small_cli_render("scenes/tncg15_room.json", "whitted", &[], &exr);
    let log = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{log}");
    assert!(
        log.contains("whitted is biased: it leaves out indirect diffuse light and caustics"),
        "{log}"
    );
    let (_, meta) = hexray::film::output::read_exr(&exr).unwrap();
    assert_eq!(meta.get("omits"), Method::Whitted.omits());
}
