//! Grazing angles: a diffuse plane (albedo ρ = 0.8, 0.5, 0.2) splits a closed enclosure whose
//! upper half emits Le = 1 inward (black emitters) and whose lower half is black
//! (`scenes/stability/grazing.json`). The plane's upper side sees only the emitting half, so its
//! radiance is exactly ρ Le from every direction (E = π Le, L = ρ/π · E), and nothing lights its
//! underside. Seen at 80 to 89.9 degrees from the normal, this is where cosines near 0 make NaNs
//! and infinities, self-intersection makes a plane shadow itself, and a ray slips through it.
//!
//! The camera looks along +x from 0.01 above the plane. The plane meets the far wall on a
//! horizontal image line at sy = −(0.01 / 5.73) / tan(vfov/2): rows below it are plane (ρ Le),
//! rows above it the emitting wall (exactly Le in every sample, checked pixel by pixel), and the
//! one row it crosses is the exact mixture by area. Two views: vfov 20 (incidence 80 to 89.7
//! degrees in the rows wholly on the plane, up to 89.9 in the row the line crosses) and vfov 2
//! (89 to 89.88, up to 89.9). Statistic: per image row and channel, z = (row mean − exact) / s.e.
//! with Bonferroni's correction at α = 0.01 over rows and channels, the image mean within 4 s.e.,
//! no dropped (non-finite) sample and no plane pixel whose mean is 0. Power: a renderer that ends
//! paths after one bounce (losing the BSDF-sampled half of multiple importance sampling) and a
//! plane of albedo 2 % below the scene's are rejected.
//!
//! From 0.01 below the plane, looking along +x, the plane's underside fills the upper half of
//! the image at the same grazing angles: every sample must be exactly 0 (a deterministic
//! property). Power: the plane with one of its two triangles removed lets the sky through.

use crate::common::*;
use hexray::film::Film;
use hexray::scene::{MaterialDesc, Scene, SceneDesc};
use hexray::transport::faults::Faults;
use hexray::transport::method::Method;

const SCENE: &str = "scenes/stability/grazing.json";
const SIZE: u32 = 64;
const SPP: u32 = 64;

fn narrow(d: &mut SceneDesc) {
    d.camera.vfov_deg = 2.0;
}

fn below(d: &mut SceneDesc) {
    d.camera.eye[2] -= 0.02;
    d.camera.look_at[2] -= 0.02;
}

/// The exact image: per row, the share f of the row below the plane–wall line, and
/// f ρ Le + (1 − f) Le in each of its pixels.
fn exact_image(d: &SceneDesc, width: u32, height: u32) -> Vec<[f64; 3]> {
    let plane: Vec<[f64; 3]> = d
        .triangles
        .iter()
        .filter(|t| t.material == "plane")
        .flat_map(|t| t.v)
        .collect();
    let zp = plane[0][2];
    assert!(
        plane.iter().all(|v| v[2] == zp),
        "the plane is not z = const"
    );
    let far = plane.iter().map(|v| v[0]).fold(f64::MIN, f64::max);
    let c = &d.camera;
    assert!(
        c.eye[1] == 0.0
            && c.look_at[1] == 0.0
            && c.look_at[2] == c.eye[2]
            && c.look_at[0] > c.eye[0]
            && c.up == [0.0, 0.0, 1.0]
            && c.eye[2] > zp,
        "the exact image assumes a camera above the plane looking along +x with up +z"
    );
    let rho = match d.materials["plane"] {
        MaterialDesc::Diffuse { albedo } => albedo,
        ref m => panic!("plane is {m:?}"),
    };
    let le = match d.materials["sky"] {
        MaterialDesc::Emitter { radiance, .. } => radiance,
        ref m => panic!("sky is {m:?}"),
    };
    let line = -((c.eye[2] - zp) / (far - c.eye[0])) / (c.vfov_deg.to_radians() * 0.5).tan();
    let mut img = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        let (lo, hi) = (
            1.0 - 2.0 * (y + 1) as f64 / height as f64,
            1.0 - 2.0 * y as f64 / height as f64,
        );
        let f = ((line - lo) / (hi - lo)).clamp(0.0, 1.0);
        for _ in 0..width {
            img.push([0, 1, 2].map(|c| f * rho[c] * le[c] + (1.0 - f) * le[c]));
        }
    }
    img
}

/// The rows test, plus the pixels that break a deterministic rule: a plane pixel whose mean is
/// not positive, or a pixel of a row wholly on the emitting wall (exact value Le) that is not Le
/// in every sample (mean Le, variance 0).
fn report(film: &Film, exact_of: &SceneDesc) -> (TruthReport, usize) {
    report_with(film, exact_of, true)
}

/// [`report`], with the rows wholly on the wall tested only where `exact_wall`. BDPT's wall
/// pixels are Le only on average: MIS shares them between the camera subpath that hits the wall
/// (weight 1 − 1.2e-7 in the narrow view, one f32 ulp below 1) and the wall's light points
/// splatted into the pixel, which land in a pixel of the narrow view about once in 3000
/// iterations. A row of 64 pixels then often has no splat in 64 iterations: its mean is 1.2e-7
/// below Le with a sample variance of 0, which no z-test can judge. The plane's rows, which
/// this test is about, and the image mean (with its batch-means s.e.) are tested.
fn report_with(film: &Film, exact_of: &SceneDesc, exact_wall: bool) -> (TruthReport, usize) {
    let exact = exact_image(exact_of, SIZE, SIZE);
    let le = match exact_of.materials["sky"] {
        MaterialDesc::Emitter { radiance, .. } => radiance,
        ref m => panic!("sky is {m:?}"),
    };
    let bad = film
        .pixels
        .iter()
        .zip(&exact)
        .filter(|(p, e)| {
            let (m, v) = (p.mean(), p.var_of_mean());
            if **e == le {
                exact_wall && (m != le || v != [0.0; 3])
            } else {
                (0..3).any(|c| e[c] > 0.0 && m[c] <= 0.0)
            }
        })
        .count();
    let plane_rows = |x: u32, y: u32| {
        let e = exact[(y * SIZE + x) as usize];
        (exact_wall || e != le).then_some(y as usize)
    };
    (against_truth(film, &exact, plane_rows, 0.01), bad)
}

/// A path-traced render of a scene on `backend` with the seed `cpu_seed` or `gpu_seed`.
fn render(
    backend: Backend,
    scene: &Scene,
    (cpu_seed, gpu_seed): (u32, u32),
    faults: Faults,
) -> Film {
    let seed = match backend {
        Backend::Cpu => cpu_seed,
        Backend::Gpu => gpu_seed,
    };
    Render::scene(scene)
        .size(SIZE, SIZE)
        .spp(SPP)
        .seed(seed)
        .faults(faults)
        .on(backend)
}

/// Renders `view` of the scene (after `planted`, a change the exact image does not know about)
/// on `backend` (seed 60 + the view's on the CPU, 62 + the view's on the GPU) and compares it
/// with the exact image of `view`.
fn grazing(
    backend: Backend,
    view: View,
    planted: fn(&mut SceneDesc),
    faults: Faults,
) -> (TruthReport, usize) {
    let truth = load_changed(SCENE, view.change);
    let scene = load_changed(SCENE, |d| {
        (view.change)(d);
        planted(d);
    });
    let seeds = (60 + view.seed, 62 + view.seed);
    report(&render(backend, &scene, seeds, faults), &truth.desc)
}

/// A camera for the exact-image test, with its own seed: the sampler's streams depend on the
/// seed, pixel and sample only, so two views rendered with one seed would draw the same numbers
/// and have correlated errors.
#[derive(Clone, Copy)]
struct View {
    change: fn(&mut SceneDesc),
    seed: u32,
}

/// vfov 20 degrees: the plane rows at incidence 80 to 89.7 degrees.
const WIDE: View = View {
    change: unchanged,
    seed: 0,
};
/// vfov 2 degrees: the plane rows at incidence 89 to 89.9 degrees.
const NARROW: View = View {
    change: narrow,
    seed: 1,
};

fn unchanged(_: &mut SceneDesc) {}

fn assert_exact(what: &str, (r, bad): (TruthReport, usize)) {
    eprintln!(
        "{what}: {}; {bad} plane pixels at 0 or wall pixels not exactly Le",
        r.summary()
    );
    assert!(
        r.agrees() && bad == 0,
        "{what}: {}; {bad} plane pixels at 0 or wall pixels not exactly Le",
        r.summary()
    );
}

fn assert_rejected(what: &str, (r, _): (TruthReport, usize)) {
    r.assert_rejected_as_too_dark(what);
}

on_each_backend! {
    fn grazing_plane_is_albedo_times_le_at_80_to_89_7_degrees(backend) {
        let r = grazing(backend, WIDE, unchanged, Faults::NONE);
        assert_exact(&format!("{backend} grazing 80-89.7"), r);
    }

    fn grazing_plane_is_albedo_times_le_at_89_to_89_9_degrees(backend) {
        let r = grazing(backend, NARROW, unchanged, Faults::NONE);
        assert_exact(&format!("{backend} grazing 89-89.9"), r);
    }
}

const ONE_BOUNCE: Faults = Faults {
    max_bounces: 1,
    ..Faults::NONE
};

fn albedo_2_percent_low(d: &mut SceneDesc) {
    let albedo = [0.8, 0.5, 0.2].map(|a| a * 0.98);
    d.materials
        .insert("plane".into(), MaterialDesc::Diffuse { albedo });
}

on_each_backend! {
    fn grazing_test_rejects_one_bounce_paths(backend) {
        let r = grazing(backend, WIDE, unchanged, ONE_BOUNCE);
        assert_rejected(&format!("{backend} grazing, one bounce"), r);
    }
}

#[test]
fn grazing_test_rejects_an_albedo_2_percent_low_on_the_cpu() {
    assert_rejected(
        "CPU grazing, albedo 2 % low",
        grazing(Backend::Cpu, WIDE, albedo_2_percent_low, Faults::NONE),
    );
}

/// Pixels with light seen from below the plane (seed 64 on the CPU, 65 on the GPU).
fn from_below(backend: Backend, planted: fn(&mut SceneDesc)) -> (usize, u64) {
    let scene = load_changed(SCENE, |d| {
        below(d);
        planted(d);
    });
    let film = render(backend, &scene, (64, 65), Faults::NONE);
    (lit_pixels(&film).len(), film.dropped())
}

fn remove_a_plane_triangle(d: &mut SceneDesc) {
    let i = d
        .triangles
        .iter()
        .position(|t| t.material == "plane")
        .unwrap();
    d.triangles.remove(i);
}

fn assert_dark_below(backend: Backend, (lit, dropped): (usize, u64)) {
    eprintln!("{backend} under the grazing plane: {lit} lit pixels, {dropped} dropped");
    assert_eq!(lit, 0, "{backend}: light under the plane in {lit} pixels");
    assert_eq!(dropped, 0);
}

on_each_backend! {
    fn grazing_plane_lets_no_light_through(backend) {
        assert_dark_below(backend, from_below(backend, unchanged));
    }

    /// Power: through a missing triangle the sky is seen from below.
    fn grazing_leak_test_rejects_a_missing_triangle(backend) {
        let (lit, _) = from_below(backend, remove_a_plane_triangle);
        eprintln!("{backend} under a plane missing a triangle: {lit} lit pixels");
        assert!(lit > 0, "{backend}: a hole in the plane went unnoticed");
    }
}

// BDPT on the same views: the plane at grazing incidence is lit by next-event estimation,
// by the camera subpaths that hit the wall and by the wall's light points splatted through the
// plane's vertices, all weighted by MIS; the rows must still be exactly albedo x Le.

on_each_backend! {
    /// Seed 66 + the view's on the CPU, 68 + the view's on the GPU.
    fn grazing_plane_is_albedo_times_le_with_bdpt(backend) {
        let seed = match backend {
            Backend::Cpu => 66,
            Backend::Gpu => 68,
        };
        for view in [WIDE, NARROW] {
            let truth = load_changed(SCENE, view.change);
            let film = Render::scene(&truth)
                .size(SIZE, SIZE)
                .spp(SPP)
                .seed(seed + view.seed)
                .method(Method::Bdpt)
                .on(backend);
            let r = report_with(&film, &truth.desc, false);
            assert_exact(&format!("{backend} BDPT grazing, view {}", view.seed), r);
        }
    }
}
