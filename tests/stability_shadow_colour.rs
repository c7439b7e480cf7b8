//! Shadows keep their colour (the course report's other bug: "shadows lose colour"): where no
//! point of the light is visible, a diffuse patch's radiance is ρ ⊙ E/π, E the irradiance of the
//! indirect light, so it has the albedo's hue times the indirect light's hue. The view
//! (`scenes/stability/tncg15_umbra_view.json`: tncg15_room, camera between the tetrahedron and
//! the red wall) shows the tetrahedron's cyan face y = 4, whose plane hides the whole light, lit
//! by the red wall, and the white floor strip in the tetrahedron's cast shadow.
//!
//! Exact expectation: for each pixel whose whole footprint is in the umbra, the rendered pixel
//! mean equals a gather estimate at the same hit points: jitter in the pixel, first hit,
//! a cosine-distributed direction ω about the facing normal, and ρ ⊙ L_in(ω), L_in from the CPU
//! path tracer started on a ray leaving the patch (cosine sampling makes (1/π)∫ L_in cos θ dω the
//! mean of L_in). What is independent of the renderer: the umbra (decided in f64 by this file's
//! own ray casts from 4x4 points of each pixel's footprint, edges included, to a 13x13 grid of
//! points on each light triangle enlarged by 5 % past its edges, then eroded by one pixel), the
//! first vertex's estimator (the cosine warp, the multiplication by ρ, no light sampling and no
//! MIS there), and the seeds. Shared: the camera's f32 rays and the closest-hit query for the
//! gather's first vertex, `offset_ray_origin`, and `trace_path` for L_in (its own correctness is
//! the other tests' subject). A renderer that greys the indirect light, drops ρ at the first
//! vertex, or adds light in the umbra differs from this expectation.
//!
//! Statistics: per region (the cyan face, the white floor), the ratio of the render's region
//! mean to the gather's, per channel, with its standard error from the per-pixel variances of
//! both (independent seeds): |ratio − 1| ≤ 4 s.e. The hue statement: the render's channel ratios
//! R/G and B/G equal those of ρ times those of the gathered irradiance, within 4 s.e., where the
//! s.e. of a ratio of two channels of one image is bounded by σ_a/a + σ_b/b (the film keeps no
//! cross-channel covariance; this bound holds for any correlation); and the gathered irradiance
//! is not grey (its own hue differs from grey by more than 4 s.e.), so the statement has content.
//! A renderer that greys the light gathered after the first diffuse bounce
//! (`Faults::grey_indirect`) is rejected by both, on the CPU and on the GPU.

use crate::common::*;
use glam::{DVec3, Vec3};
use hexray::accel::bvh::intersect_closest;
use hexray::analysis::stats::MeanImage;
use hexray::cpu::trace_path;
use hexray::film::{Film, PixelStats};
use hexray::layout::FlatScene;
use hexray::math::geometry::offset_ray_origin;
use hexray::scene::{MaterialDesc, Scene};
use hexray::transport::camera::Camera;
use hexray::transport::faults::Faults;
use rayon::prelude::*;
use std::sync::{Arc, OnceLock};

const VIEW: &str = "scenes/stability/tncg15_umbra_view.json";
const SIZE: u32 = 64;
/// Samples per pixel of the renders.
const SPP: u32 = 128;
/// Gather samples per umbra pixel.
const GATHER: u32 = 128;
const GREY: Faults = Faults {
    grey_indirect: true,
    ..Faults::NONE
};

/// The two umbra regions: the tetrahedron's face toward the red wall, and the floor.
const REGIONS: [&str; 2] = ["cyan", "white"];

// ---- The umbra, in f64 -------------------------------------------------------------------

struct Geometry {
    /// (vertices, material name, is a light)
    triangles: Vec<([DVec3; 3], String, bool)>,
    spheres: Vec<(DVec3, f64)>,
}

impl Geometry {
    fn new(scene: &Scene) -> Geometry {
        let emitter = |m: &str| matches!(scene.desc.materials[m], MaterialDesc::Emitter { .. });
        Geometry {
            triangles: scene
                .desc
                .triangles
                .iter()
                .map(|t| {
                    (
                        t.v.map(DVec3::from),
                        t.material.clone(),
                        emitter(&t.material),
                    )
                })
                .collect(),
            spheres: scene
                .desc
                .spheres
                .iter()
                .map(|s| (DVec3::from(s.center), s.radius))
                .collect(),
        }
    }

    /// Möller–Trumbore in f64: the ray parameter, if the ray meets the triangle at t > 0.
    fn triangle_t(o: DVec3, d: DVec3, v: &[DVec3; 3]) -> Option<f64> {
        let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-300 {
            return None;
        }
        let s = o - v[0];
        let b1 = s.dot(p) / det;
        let q = s.cross(e1);
        let b2 = d.dot(q) / det;
        let t = e2.dot(q) / det;
        (b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 && t > 0.0).then_some(t)
    }

    fn sphere_t(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<f64> {
        let (f, a) = (o - c, d.dot(d));
        let b = f.dot(d);
        let disc = b * b - a * (f.dot(f) - r * r);
        if disc < 0.0 {
            return None;
        }
        let (t0, t1) = ((-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a);
        [t0, t1].into_iter().find(|&t| t > 0.0)
    }

    /// The closest triangle hit (index and t); None when a sphere or nothing is closer.
    fn first_triangle(&self, o: DVec3, d: DVec3) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        for (i, (v, _, _)) in self.triangles.iter().enumerate() {
            if let Some(t) = Self::triangle_t(o, d, v) {
                if best.is_none_or(|(_, b)| t < b) {
                    best = Some((i, t));
                }
            }
        }
        let (i, t) = best?;
        let sphere_first = self
            .spheres
            .iter()
            .any(|&(c, r)| Self::sphere_t(o, d, c, r).is_some_and(|ts| ts < t));
        (!sphere_first).then_some((i, t))
    }

    /// Points on each light triangle, enlarged by 5 % past its edges: p = v0 + a e1 + b e2 for
    /// a, b on a 13x13 grid over [-0.05, 1.05] with a + b <= 1.05.
    fn light_points(&self) -> Vec<(DVec3, DVec3)> {
        let mut out = Vec::new();
        for (v, _, light) in &self.triangles {
            if !light {
                continue;
            }
            let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
            let n = e1.cross(e2).normalize();
            for i in 0..13 {
                for j in 0..13 {
                    let (a, b) = (-0.05 + 1.1 * i as f64 / 12.0, -0.05 + 1.1 * j as f64 / 12.0);
                    if a + b <= 1.05 {
                        out.push((v[0] + a * e1 + b * e2, n));
                    }
                }
            }
        }
        out
    }

    /// No light point is visible from p on triangle `on`, from the side `n_facing` faces: each
    /// is behind the patch, or behind the light's emitting side, or some other surface cuts the
    /// segment.
    fn in_umbra(&self, p: DVec3, on: usize, n_facing: DVec3, lights: &[(DVec3, DVec3)]) -> bool {
        lights.iter().all(|&(q, nl)| {
            let d = q - p;
            if n_facing.dot(d) <= 0.0 || nl.dot(-d) <= 0.0 {
                return true;
            }
            let cut = |t: f64| t > 1e-9 && t < 1.0 - 1e-9;
            self.triangles.iter().enumerate().any(|(i, (v, _, light))| {
                i != on && !light && Self::triangle_t(p, d, v).is_some_and(cut)
            }) || self
                .spheres
                .iter()
                .any(|&(c, r)| Self::sphere_t(p, d, c, r).is_some_and(cut))
        })
    }
}

/// The camera's ray through image position (x, y) in f64 (the same pinhole as `Camera`).
fn camera_ray_f64(scene: &Scene, x: f64, y: f64) -> (DVec3, DVec3) {
    let c = &scene.desc.camera;
    let eye = DVec3::from(c.eye);
    let forward = (DVec3::from(c.look_at) - eye).normalize();
    let right = forward.cross(DVec3::from(c.up)).normalize();
    let up = right.cross(forward);
    let tan = (c.vfov_deg.to_radians() * 0.5).tan();
    let sx = 2.0 * x / SIZE as f64 - 1.0;
    let sy = 1.0 - 2.0 * y / SIZE as f64;
    (
        eye,
        (forward + sx * tan * right + sy * tan * up).normalize(),
    )
}

/// Each pixel's region (an index into REGIONS) when its whole footprint is in the umbra of one
/// diffuse surface of that material, and so are its eight neighbours'.
fn umbra_mask(scene: &Scene) -> Vec<Option<usize>> {
    let geo = Geometry::new(scene);
    let lights = geo.light_points();
    let raw: Vec<Option<usize>> = (0..SIZE * SIZE)
        .into_par_iter()
        .map(|pixel| {
            let (px, py) = ((pixel % SIZE) as f64, (pixel / SIZE) as f64);
            let mut region = None;
            for i in 0..4 {
                for j in 0..4 {
                    let (o, d) = camera_ray_f64(scene, px + i as f64 / 3.0, py + j as f64 / 3.0);
                    let (tri, t) = geo.first_triangle(o, d)?;
                    let (v, material, _) = &geo.triangles[tri];
                    let r = REGIONS.iter().position(|m| m == material)?;
                    if region.is_some_and(|q| q != r) {
                        return None;
                    }
                    region = Some(r);
                    let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
                    let n_facing = if n.dot(d) > 0.0 { -n } else { n };
                    if !geo.in_umbra(o + t * d, tri, n_facing, &lights) {
                        return None;
                    }
                }
            }
            region
        })
        .collect();
    let s = SIZE as i64;
    (0..s * s)
        .map(|i| {
            let (x, y) = (i % s, i / s);
            let r = raw[i as usize]?;
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx < 0
                        || ny < 0
                        || nx >= s
                        || ny >= s
                        || raw[(ny * s + nx) as usize] != Some(r)
                    {
                        return None;
                    }
                }
            }
            Some(r)
        })
        .collect()
}

// ---- The gather ------------------------------------------------------------------------

/// A camera whose only ray is `o + t d`: `trace_path` started on a ray leaving a surface.
fn probe(o: Vec3, d: Vec3) -> Camera {
    Camera {
        eye: o.into(),
        width: 1,
        forward: d.into(),
        height: 1,
        right: [0.0; 3],
        pad0: 0,
        up: [0.0; 3],
        pad1: 0,
    }
}

/// Per umbra pixel, `GATHER` estimates of ρ ⊙ (1/π)∫ L_in cos θ dω at first hits spread over
/// the pixel's footprint; other pixels stay empty.
fn gather(scene: &Scene, flat: &FlatScene, mask: &[Option<usize>]) -> Film {
    let camera = Camera::new(&scene.desc.camera, SIZE, SIZE);
    let albedo = |r: usize| match scene.desc.materials[REGIONS[r]] {
        MaterialDesc::Diffuse { albedo } => DVec3::from(albedo),
        _ => unreachable!(),
    };
    let material_id = |r: usize| {
        scene
            .desc
            .materials
            .keys()
            .position(|k| k == REGIONS[r])
            .unwrap() as u32
    };
    let pixels: Vec<PixelStats> = (0..SIZE * SIZE)
        .into_par_iter()
        .map(|pixel| {
            let mut stats = PixelStats::default();
            let Some(r) = mask[pixel as usize] else {
                return stats;
            };
            let mut rays = 0u64;
            for k in 0..GATHER {
                let u = hexray::math::sampling::Sampler::new(41, pixel, k).draw4(0);
                let ray = camera.ray(pixel % SIZE, pixel / SIZE, u[0], u[1]);
                let hit = intersect_closest(flat, &ray, f32::MAX).expect("an umbra pixel's ray");
                assert_eq!(
                    hit.material,
                    material_id(r),
                    "pixel {pixel} left its region"
                );
                let n = if hit.n.dot(ray.d) > 0.0 {
                    -hit.n
                } else {
                    hit.n
                };
                // Malley's method in f64: a uniform point on the disk lifted to the hemisphere.
                let n64 = n.as_dvec3();
                let t = if n64.x.abs() > 0.9 {
                    DVec3::Y
                } else {
                    DVec3::X
                };
                let t = n64.cross(t).normalize();
                let b = n64.cross(t);
                let (rad, phi) = ((u[2] as f64).sqrt(), std::f64::consts::TAU * u[3] as f64);
                let z = (1.0 - u[2] as f64).max(0.0).sqrt();
                let w = (rad * phi.cos() * t + rad * phi.sin() * b + z * n64)
                    .normalize()
                    .as_vec3();
                let o = offset_ray_origin(hit.p, hit.p_err, hit.n, w);
                let sampler = hexray::math::sampling::Sampler::new(42, pixel, k);
                let l_in = trace_path(
                    flat,
                    &probe(o, w),
                    0,
                    0,
                    &sampler,
                    1,
                    Faults::NONE,
                    &mut rays,
                );
                stats.add((albedo(r) * l_in.as_dvec3()).as_vec3());
            }
            stats
        })
        .collect();
    Film {
        pixels,
        ..Film::new(SIZE, SIZE)
    }
}

struct Setup {
    mask: Vec<Option<usize>>,
    gather: MeanImage,
    albedo: [DVec3; 2],
}

fn setup() -> &'static Setup {
    static SETUP: OnceLock<Setup> = OnceLock::new();
    SETUP.get_or_init(|| {
        let (scene, flat) = load(VIEW);
        let mask = umbra_mask(&scene);
        for (r, name) in REGIONS.iter().enumerate() {
            let n = mask.iter().filter(|m| **m == Some(r)).count();
            eprintln!("umbra region {name}: {n} pixels");
            assert!(n >= 64, "the {name} umbra region has only {n} pixels");
        }
        let gather = MeanImage::from_film(&gather(&scene, &flat, &mask));
        let albedo = REGIONS.map(|m| match scene.desc.materials[m] {
            MaterialDesc::Diffuse { albedo } => DVec3::from(albedo),
            _ => unreachable!(),
        });
        Setup {
            mask,
            gather,
            albedo,
        }
    })
}

/// Region means of an image over the pixels of region r, with their standard errors.
fn region_mean(img: &MeanImage, mask: &[Option<usize>], r: usize) -> ([f64; 3], [f64; 3]) {
    let pixels: Vec<usize> = (0..mask.len()).filter(|&i| mask[i] == Some(r)).collect();
    let k = pixels.len() as f64;
    let (mut m, mut v) = ([0.0; 3], [0.0; 3]);
    for &i in &pixels {
        for c in 0..3 {
            m[c] += img.mean[i][c] / k;
            v[c] += img.var[i][c] / (k * k);
        }
    }
    (m, v.map(f64::sqrt))
}

/// Per region and channel, z of the ratio render / gather against 1.
fn radiance_z(render: &Film) -> Vec<[f64; 3]> {
    let s = setup();
    let img = MeanImage::from_film(render);
    (0..REGIONS.len())
        .map(|r| {
            let (a, sa) = region_mean(&img, &s.mask, r);
            let (g, sg) = region_mean(&s.gather, &s.mask, r);
            let z = [0, 1, 2].map(|c| {
                let ratio = a[c] / g[c];
                let se = ratio * ((sa[c] / a[c]).powi(2) + (sg[c] / g[c]).powi(2)).sqrt();
                (ratio - 1.0) / se
            });
            eprintln!(
                "{}: render {:.5} {:.5} {:.5}, gather ρ ⊙ E/π {:.5} {:.5} {:.5}, ratio z {:.2} {:.2} {:.2}",
                REGIONS[r], a[0], a[1], a[2], g[0], g[1], g[2], z[0], z[1], z[2]
            );
            z
        })
        .collect()
}

/// The ratio of channels a / b of a region mean, and a bound on its relative s.e.
fn hue(m: [f64; 3], s: [f64; 3], a: usize, b: usize) -> (f64, f64) {
    (m[a] / m[b], s[a] / m[a] + s[b] / m[b])
}

/// Per region and hue ratio (R/G, B/G): z of the render's hue against ρ's hue times the
/// gathered irradiance's hue; and z of the irradiance's hue against grey.
fn hue_z(render: &Film) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
    let s = setup();
    let img = MeanImage::from_film(render);
    let (mut against_expected, mut irradiance_vs_grey) = (Vec::new(), Vec::new());
    for (r, region) in REGIONS.iter().enumerate() {
        let (a, sa) = region_mean(&img, &s.mask, r);
        let (g, sg) = region_mean(&s.gather, &s.mask, r);
        let rho = s.albedo[r].to_array();
        // The gathered E/π is the gather over ρ, channel by channel (ρ is exact).
        let e = [0, 1, 2].map(|c| g[c] / rho[c]);
        let se = [0, 1, 2].map(|c| sg[c] / rho[c]);
        let mut zs = [0.0; 2];
        let mut zg = [0.0; 2];
        for (k, c) in [0usize, 2].into_iter().enumerate() {
            let (h_render, rel_render) = hue(a, sa, c, 1);
            let (h_e, rel_e) = hue(e, se, c, 1);
            let expected = rho[c] / rho[1] * h_e;
            let rel = (rel_render * rel_render + rel_e * rel_e).sqrt();
            zs[k] = (h_render / expected - 1.0) / rel;
            zg[k] = (h_e - 1.0) / (h_e * rel_e);
            eprintln!(
                "{} {}/G: render {:.4}, ρ {:.4} x E {:.4} = {:.4} (z {:.2}); E against grey z {:.1}",
                region,
                ["R", "", "B"][c],
                h_render,
                rho[c] / rho[1],
                h_e,
                expected,
                zs[k],
                zg[k]
            );
        }
        against_expected.push(zs);
        irradiance_vs_grey.push(zg);
    }
    (against_expected, irradiance_vs_grey)
}

/// The umbra view on `backend`, correct or with grey indirect light (seeds 51 and 52 on the
/// CPU, where it is rendered once for all tests; 53 and 54 on the GPU).
fn view(backend: Backend, faults: Faults) -> Arc<Film> {
    let seed = match (backend, faults == GREY) {
        (Backend::Cpu, false) => 51,
        (Backend::Cpu, true) => 52,
        (Backend::Gpu, false) => 53,
        (Backend::Gpu, true) => 54,
    };
    let render = Render::file(VIEW)
        .size(SIZE, SIZE)
        .spp(SPP)
        .seed(seed)
        .faults(faults);
    match backend {
        Backend::Cpu => render.cpu_shared(),
        Backend::Gpu => Arc::new(render.gpu()),
    }
}

fn assert_radiance_matches(render: &Film, what: &str) {
    for (r, z) in radiance_z(render).iter().enumerate() {
        assert!(
            z.iter().all(|z| z.abs() <= 4.0),
            "{what}: {} umbra differs from ρ ⊙ E/π: z {z:?}",
            REGIONS[r]
        );
    }
}

fn radiance_rejected(render: &Film) -> bool {
    radiance_z(render)
        .iter()
        .any(|z| z.iter().any(|z| z.abs() > 4.0))
}

on_each_backend! {
    fn umbra_radiance_is_albedo_times_gathered_irradiance(backend) {
        assert_radiance_matches(&view(backend, Faults::NONE), &backend.to_string());
    }

    /// Power: a renderer whose light after the first diffuse bounce is grey fails both
    /// statements (the hue statement is tested on the CPU only).
    fn umbra_tests_reject_grey_indirect_light(backend) {
        let grey = view(backend, GREY);
        assert!(
            radiance_rejected(&grey),
            "{backend}: grey indirect light passed the radiance test"
        );
        if backend == Backend::Cpu {
            let (z, _) = hue_z(&grey);
            assert!(
                z.iter().any(|z| z.iter().any(|z| z.abs() > 4.0)),
                "grey indirect light passed the hue test: {z:?}"
            );
        }
    }
}

#[test]
fn cpu_umbra_hue_is_albedo_hue_times_irradiance_hue() {
    let (z, e_vs_grey) = hue_z(&view(Backend::Cpu, Faults::NONE));
    // The statement has content: the cyan face's indirect light is measurably coloured.
    assert!(
        e_vs_grey[0].iter().all(|z| z.abs() > 4.0),
        "the cyan face's irradiance is grey: z {:?}",
        e_vs_grey[0]
    );
    for (r, z) in z.iter().enumerate() {
        assert!(
            z.iter().all(|z| z.abs() <= 4.0),
            "{} umbra hue is not ρ's times E's: z {z:?}",
            REGIONS[r]
        );
    }
}
