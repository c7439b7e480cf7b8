//! Chi-square goodness-of-fit tests of the two sampling routines the integrator relies on, in
//! pbrt's recipe (pbrt-v3 src/tests/bsdfs.cpp): bin 10^6 sampled directions into 80 x 160
//! (θ, φ) cells over the sphere, integrate the claimed pdf over each cell for the expected
//! counts, pool cells expecting fewer than 5, and run Pearson's test. The family of tests has
//! level α = 0.01 with Šidák's correction, 1 − (1 − α)^(1/m) per test. A sampler whose pdf
//! (used by MIS and by the estimator's weights) disagrees with what it samples is rejected; the
//! last two tests plant such a disagreement and show it.

use glam::Vec3;
use hexray::analysis::stats::chi_square_test;
use hexray::layout::{FlatScene, Material, KIND_DIFFUSE, PRIM_SPHERE_BIT};
use hexray::math::geometry::{intersect_triangle, Ray};
use hexray::math::sampling::Sampler;
use hexray::scene::Scene;
use hexray::transport::bsdf::{sample_bsdf, Transport};
use hexray::transport::light::sample_emitter;
use std::f64::consts::PI;

const THETA_BINS: usize = 80;
const PHI_BINS: usize = 160;
const SAMPLES: u32 = 1_000_000;
/// Six tests share α = 0.01.
const TESTS_IN_FAMILY: f64 = 6.0;

fn sidak_level() -> f64 {
    1.0 - (1.0 - 0.01f64).powf(1.0 / TESTS_IN_FAMILY)
}

fn bin_of(w: Vec3) -> usize {
    let w = w.as_dvec3().normalize();
    let theta = w.z.clamp(-1.0, 1.0).acos();
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let t = ((theta / PI * THETA_BINS as f64) as usize).min(THETA_BINS - 1);
    let p = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
    t * PHI_BINS + p
}

fn dir(theta: f64, phi: f64) -> Vec3 {
    Vec3::new(
        (theta.sin() * phi.cos()) as f32,
        (theta.sin() * phi.sin()) as f32,
        theta.cos() as f32,
    )
}

/// Integral of pdf(ω) sinθ dθ dφ over one cell by the midpoint rule on a k x k grid.
fn integrate_cell(pdf: &dyn Fn(Vec3) -> f64, t: usize, p: usize, k: usize) -> (f64, usize) {
    let (dt, dp) = (PI / THETA_BINS as f64, 2.0 * PI / PHI_BINS as f64);
    let (mut sum, mut nonzero) = (0.0, 0);
    for i in 0..k {
        for j in 0..k {
            let theta = (t as f64 + (i as f64 + 0.5) / k as f64) * dt;
            let phi = (p as f64 + (j as f64 + 0.5) / k as f64) * dp;
            let v = pdf(dir(theta, phi));
            if v > 0.0 {
                nonzero += 1;
            }
            sum += v * theta.sin();
        }
    }
    (sum * dt * dp / (k * k) as f64, nonzero)
}

/// Expected counts. A 4 x 4 look at each cell finds the support of the pdf; cells on or next to
/// its edge (where part of a cell, or a sliver the look missed, has zero pdf and the midpoint
/// rule converges slowly) get a 64 x 64 grid, cells well inside it 16 x 16.
fn expected_counts(pdf: &dyn Fn(Vec3) -> f64, n: f64) -> Vec<f64> {
    let look: Vec<usize> = (0..THETA_BINS * PHI_BINS)
        .map(|i| integrate_cell(pdf, i / PHI_BINS, i % PHI_BINS, 4).1)
        .collect();
    let mut out = vec![0.0; THETA_BINS * PHI_BINS];
    for t in 0..THETA_BINS {
        for p in 0..PHI_BINS {
            let mut near = Vec::new();
            for dt in [-1i64, 0, 1] {
                for dp in [-1i64, 0, 1] {
                    let tt = t as i64 + dt;
                    if (0..THETA_BINS as i64).contains(&tt) {
                        let pp = (p as i64 + dp).rem_euclid(PHI_BINS as i64);
                        near.push(look[tt as usize * PHI_BINS + pp as usize]);
                    }
                }
            }
            let k = if near.iter().all(|&c| c == 16) {
                16
            } else if near.iter().any(|&c| c > 0) {
                64
            } else {
                continue;
            };
            out[t * PHI_BINS + p] = n * integrate_cell(pdf, t, p, k).0;
        }
    }
    out
}

fn histogram(mut sample: impl FnMut(u32) -> Option<Vec3>) -> Vec<f64> {
    let mut h = vec![0.0; THETA_BINS * PHI_BINS];
    for i in 0..SAMPLES {
        if let Some(w) = sample(i) {
            h[bin_of(w)] += 1.0;
        }
    }
    h
}

fn chi_square_p(observed: &[f64], expected: &[f64], what: &str) -> f64 {
    let total: f64 = expected.iter().sum();
    // The integrated pdf must account for every sample (to the quadrature's accuracy).
    assert!(
        (total / SAMPLES as f64 - 1.0).abs() < 2e-3,
        "{what}: pdf integrates to {}",
        total / SAMPLES as f64
    );
    let (stat, dof, p) = chi_square_test(observed, expected);
    eprintln!("{what}: chi2 = {stat:.1} with {dof} dof, p = {p:.3e}");
    p
}

fn diffuse_material() -> Material {
    Material {
        color: [1.0; 3],
        kind: KIND_DIFFUSE,
        ..Default::default()
    }
}

fn cosine_p(n: Vec3, wo: Vec3, claimed_pdf: &dyn Fn(Vec3) -> f64) -> f64 {
    let m = diffuse_material();
    let observed = histogram(|i| {
        Some(
            sample_bsdf(
                &m,
                n,
                wo,
                Sampler::new(5, i, 0).draw4(2),
                Transport::Radiance,
            )
            .wi,
        )
    });
    let expected = expected_counts(claimed_pdf, SAMPLES as f64);
    chi_square_p(&observed, &expected, "cosine sampling")
}

fn cosine_pdf(nf: Vec3) -> impl Fn(Vec3) -> f64 {
    move |w: Vec3| (nf.dot(w) as f64).max(0.0) / PI
}

#[test]
fn cosine_sampling_matches_its_pdf() {
    let tilted = Vec3::new(0.3, -0.5, 0.81).normalize();
    // Two-sided: with wo below the surface, directions are sampled about -n.
    for (n, wo, nf) in [
        (Vec3::Z, Vec3::new(0.0, 0.6, 0.8), Vec3::Z),
        (tilted, tilted, tilted),
        (tilted, -tilted, -tilted),
    ] {
        let p = cosine_p(n, wo, &cosine_pdf(nf));
        assert!(p > sidak_level(), "cosine sampling about {nf}: p = {p:.3e}");
    }
}

/// Emitters of different power, size and orientation, one seen edge-on from below.
const EMITTERS: &str = r#"{
 "camera": { "eye": [0, 0, 0], "look_at": [1, 0, 0], "up": [0, 0, 1], "vfov_deg": 60 },
 "materials": {
  "dim": { "type": "emitter", "radiance": [1, 1, 1] },
  "bright": { "type": "emitter", "radiance": [6, 3, 1] },
  "blue": { "type": "emitter", "radiance": [0, 0, 2] }
 },
 "triangles": [
  { "v": [[-1, -1, 1], [1, 1, 1], [1, -1, 1]], "material": "dim" },
  { "v": [[-1, -1, 1], [-1, 1, 1], [1, 1, 1]], "material": "dim" },
  { "v": [[2, -0.5, -1], [2, 0.5, 0.5], [2, 0.5, -1]], "material": "bright" },
  { "v": [[-3, 2, -2], [-3, 4, -1], [-1, 3, 2]], "material": "blue" },
  { "v": [[0, -2, 0.5], [0.5, -3, 0.5], [-0.5, -3, 0.5]], "material": "blue" }
 ]
}"#;

/// An emitting sphere, seen from inside and off centre. (From outside, a sphere's solid-angle
/// pdf has an integrable 1/cos singularity at its silhouette that the bins' midpoint quadrature
/// cannot follow; from inside, every direction meets it once, at a bounded cos. And it has a
/// scene of its own: around the triangles it would fill every bin, and the quadrature finds the
/// triangles' edges only where the pdf drops to zero.)
const SPHERE_EMITTER: &str = r#"{
 "camera": { "eye": [0, 0, 0], "look_at": [1, 0, 0], "up": [0, 0, 1], "vfov_deg": 60 },
 "materials": { "glow": { "type": "emitter", "radiance": [1, 2, 1] } },
 "spheres": [ { "center": [0.5, 0.5, -0.5], "radius": 2, "material": "glow", "flip_normals": true } ]
}"#;

fn emitter_scene() -> FlatScene {
    scene_of(EMITTERS)
}

fn scene_of(json: &str) -> FlatScene {
    let scene = Scene::from_json(json, std::path::Path::new("emitters.json"))
        .unwrap_or_else(|e| panic!("{e}"));
    FlatScene::build(&scene, hexray::render::CpuBackend::TRAVERSAL)
}

/// The solid-angle density with which `sample_emitter` produces direction w at point p: the
/// sum, over every emitter point the ray p + t w crosses (occluded or not, front or back, both
/// crossings of a sphere), of pmf / area · t² / |cos θ_l|. `pmf` gives each table row's
/// selection probability.
fn emitter_pdf(scene: &FlatScene, p: Vec3, pmf: &dyn Fn(usize) -> f32) -> impl Fn(Vec3) -> f64 {
    let scene = scene.clone();
    let pmfs: Vec<f32> = (0..scene.emitters.len()).map(pmf).collect();
    move |w: Vec3| {
        let ray = Ray { o: p, d: w };
        let mut pdf = 0.0;
        for (k, e) in scene.emitters.iter().enumerate() {
            if e.prim & PRIM_SPHERE_BIT != 0 {
                // |p + t w - c|² = R²: t² + 2 b t + c = 0 with b = w·(p - c), in f64.
                let s = &scene.spheres[(e.prim & !PRIM_SPHERE_BIT) as usize];
                let oc = (p - Vec3::from(s.center)).as_dvec3();
                let w = w.as_dvec3();
                let b = w.dot(oc);
                let disc = b * b - (oc.length_squared() - (s.radius as f64).powi(2));
                if disc > 0.0 {
                    for t in [-b - disc.sqrt(), -b + disc.sqrt()] {
                        if t > 0.0 {
                            let n = (oc + t * w) / s.radius as f64;
                            pdf += pmfs[k] as f64 / e.area as f64 * t * t / n.dot(w).abs();
                        }
                    }
                }
                continue;
            }
            let tri = &scene.triangles[e.prim as usize];
            if let Some(h) = intersect_triangle(&ray, tri) {
                let n = hexray::math::geometry::triangle_normal(tri);
                let cos = n.dot(w).abs() as f64;
                pdf += pmfs[k] as f64 / e.area as f64 * (h.t as f64).powi(2) / cos;
            }
        }
        pdf
    }
}

fn emitter_sampling_p(p: Vec3, claimed_pmf: &dyn Fn(usize) -> f32) -> f64 {
    emitter_sampling_p_in(&emitter_scene(), p, claimed_pmf)
}

fn emitter_sampling_p_in(scene: &FlatScene, p: Vec3, claimed_pmf: &dyn Fn(usize) -> f32) -> f64 {
    let observed = histogram(|i| {
        let u = Sampler::new(9, i, 0).draw4(1);
        let ls = sample_emitter(scene, u[0], u[1], u[2]);
        Some(ls.p - p)
    });
    let expected = expected_counts(&emitter_pdf(scene, p, claimed_pmf), SAMPLES as f64);
    chi_square_p(&observed, &expected, "emitter sampling")
}

#[test]
fn emitter_sampling_matches_its_solid_angle_pdf() {
    let scene = emitter_scene();
    let pmf = |k: usize| scene.emitters[k].pmf;
    for p in [Vec3::ZERO, Vec3::new(0.3, -0.2, -0.4)] {
        let pv = emitter_sampling_p(p, &pmf);
        assert!(
            pv > sidak_level(),
            "emitter sampling from {p}: p = {pv:.3e}"
        );
    }
}

#[test]
fn sphere_emitter_sampling_matches_its_solid_angle_pdf() {
    let scene = scene_of(SPHERE_EMITTER);
    let pv = emitter_sampling_p_in(&scene, Vec3::new(0.3, -0.2, -0.4), &|_| 1.0);
    assert!(pv > sidak_level(), "sphere emitter sampling: p = {pv:.3e}");
}

/// Power: cosine samples tested against the uniform hemisphere pdf 1/2π are rejected.
#[test]
fn chi_square_rejects_cosine_samples_claimed_uniform() {
    let uniform = |w: Vec3| if w.z > 0.0 { 1.0 / (2.0 * PI) } else { 0.0 };
    let p = cosine_p(Vec3::Z, Vec3::Z, &uniform);
    assert!(p < 1e-6, "p = {p:.3e}");
}

/// Power: emitters chosen by power but claimed to be chosen uniformly are rejected.
#[test]
fn chi_square_rejects_a_wrong_emitter_selection_pdf() {
    let n = emitter_scene().emitters.len();
    let p = emitter_sampling_p(Vec3::ZERO, &|_| 1.0 / n as f32);
    assert!(p < 1e-6, "p = {p:.3e}");
}
