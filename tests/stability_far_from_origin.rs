//! Far from the origin, the image does not change: tncg15_room moved by (t, t, t) for
//! t = 1e3, 1e4, 1e5, and scaled by 1e-3 and 1e3 about the origin (radiance is scale-free), renders
//! the same image as the room itself, on the CPU and on the GPU; and no ray spawned at a real
//! path vertex of these scenes hits the triangle (or sphere) it leaves.
//!
//! Statistic for the images: `tests/gpu_parity.rs`'s, against an untranslated CPU render of
//! another seed (independent samples): per 8x8 block and channel, Welch's t-test with a
//! Bonferroni correction over the block-channels at α = 0.01 overall, and each channel's
//! image-mean ratio within 4 s.e. of 1. The images are 32x32, so that an 8x8 block holds a
//! sixteenth of the view and the mirror wall fills whole blocks: at [`POWERFUL_SPP`] the CPU test
//! rejects a room whose mirrors reflect 97 % of what they should (the planted error below; that
//! moves the image mean by only about 1 %), so a bias of the size Mitsuba 3.9.1 shows on this
//! room at 1e4 (1.8 % too bright, black crescents under the sphere) or 1e5 (20-27 % too bright)
//! could not pass. The GPU (lavapipe, about 5x slower than the CPU backend on the same two cores)
//! renders at [`GPU_SPP`], a quarter of the samples: its test is shown to reject a GPU mirror 8 %
//! too dark, and would still see Mitsuba's 1.8 % (about 5 s.e. of its ratio).
//!
//! Statistic for self-intersections: exact counts, no statistics. Camera paths are traced through
//! each scene as the integrator does (closest hits over the BVH, cosine-sampled or mirrored
//! continuations, a shadow ray toward a sampled light point at each diffuse vertex); from every
//! vertex, each spawned ray is tested against the primitive it leaves. A triangle is planar, so
//! a ray leaving it can never meet it again: any hit is spurious; a ray leaving a sphere outward
//! cannot meet it either. A single self-hit fails. Without `offset_ray_origin` the same count is
//! large (157 000 per million at 1e5: the check has power).
//!
//! Below this test's resolution (measured by `paired_bias_far_from_origin`, which traces each
//! sample with the same random numbers in both scenes): at 1e5 the image mean is +0.19 % ± 0.03
//! (red), +0.09 % ± 0.03 (green), +0.10 % ± 0.02 (blue) too bright; at 1e4 nothing is resolved
//! (+0.02 % ± 0.04 in red). At 1e5 the light's z = 4.99 rounds up by 0.0022 (+0.02 %, measured
//! by rendering the f32-rounded room at the origin); the rest, +0.16 % in red, is the spawn
//! offset, not a self-hit: a hit point's error bound is γ7 Σ|b p| ≈ 4.2e-7 |p| per coordinate,
//! 0.042 at 1e5 (5 ulps), so every spawned ray starts 0.04 inside the room and gathers the
//! radiance seen from there; direct light alone (no spawned continuation) shows no bias, and with
//! the bound cut tenfold (a temporary change) the bias halved. The rest is the f32 grid itself.
//!
//! Where f32 ends (`where_f32_ends_1e6_and_1e7_are_rejected`, not run by default): at 1e6
//! (ulp 0.0625) the light rounds onto the ceiling's plane, and which of the two coplanar
//! triangles a ray meets first is decided by rounding: the rounded room alone, rendered at the
//! origin, is 18.8 % (red) to 20.5 % (blue) darker; the offsets (0.42) add +1.0 % red. At 1e7
//! (ulp 1) the sphere's centre also moves by half a unit (into the floor), the rounded room is
//! 19-21 % darker, and the offsets (4 units, 40 % of the room's height) add +5 to +8 %. Both are
//! rejected on both backends (mean ratio 0.82 / 0.81 / 0.80 at 1e6, 0.87 / 0.84 / 0.84 at 1e7);
//! neither shows a self-hit (the offset grows with the coordinates; what fails is everything
//! else). The camera is not the cause here: its basis is computed in f64 and rounded once, and
//! its eye, an integer point, is exact up to 2^24.

use crate::common::parity::{parity, Parity};
use crate::common::*;
use glam::Vec3;
use hexray::accel::bvh::intersect_closest;
use hexray::layout::{KIND_DIFFUSE, KIND_EMITTER, PRIM_SPHERE_BIT};
use hexray::math::geometry::{
    intersect_sphere, intersect_triangle, offset_ray_origin, Ray, SurfaceHit,
};
use hexray::math::sampling::{dim_bsdf, dim_light, Sampler, DIM_CAMERA};
use hexray::transport::bsdf::{sample_bsdf, Transport};
use hexray::transport::camera::Camera;
use hexray::transport::faults::Faults;
use hexray::transport::light::sample_emitter;
use rayon::prelude::*;

pub const ROOM: &str = "scenes/tncg15_room.json";
pub const SIZE: u32 = 32;
/// Samples per pixel at which the CPU parity test rejects a 3 % dark mirror.
pub const POWERFUL_SPP: u32 = 2048;
/// The GPU's samples per pixel (see the header).
pub const GPU_SPP: u32 = 512;
/// Seed of the untranslated reference render (`tests/stability_mirror.rs` shares it).
pub const ROOM_SEED: u32 = 101;
/// Seed of the room rendered with mirrors 3 % too dark (shared with `tests/stability_mirror.rs`).
pub const DARK_MIRROR_SEED: u32 = 102;

pub const DARK_MIRROR: Faults = Faults {
    specular_scale: 0.97,
    ..Faults::NONE
};

/// The untranslated room at [`POWERFUL_SPP`], rendered once for all tests of this binary.
pub fn room_reference() -> std::sync::Arc<hexray::film::Film> {
    Render::file(ROOM)
        .size(SIZE, SIZE)
        .spp(POWERFUL_SPP)
        .seed(ROOM_SEED)
        .cpu_shared()
}

/// The room with mirrors 3 % too dark at [`POWERFUL_SPP`], rendered once for all tests.
pub fn dark_mirror_room() -> std::sync::Arc<hexray::film::Film> {
    Render::file(ROOM)
        .size(SIZE, SIZE)
        .spp(POWERFUL_SPP)
        .seed(DARK_MIRROR_SEED)
        .faults(DARK_MIRROR)
        .cpu_shared()
}

/// Each scene gets its own seeds (independent of the reference's and of each other's).
fn scene(name: &str) -> (String, u32) {
    let seed = match name {
        "translated_1e3" => 111,
        "translated_1e4" => 112,
        "translated_1e5" => 113,
        "scaled_1e-3" => 114,
        "scaled_1e3" => 115,
        "translated_1e6" => 116,
        "translated_1e7" => 117,
        _ => unreachable!(),
    };
    (format!("scenes/stability/tncg15_{name}.json"), seed)
}

/// The scene `name` against the untranslated CPU room: on the CPU at [`POWERFUL_SPP`] with its
/// seed (shared: the power test compares it too), on the GPU at [`GPU_SPP`] with its seed + 100.
fn moved_parity(backend: Backend, name: &str, faults: Faults) -> Parity {
    let (rel, seed) = scene(name);
    let render = Render::file(&rel).size(SIZE, SIZE).faults(faults);
    let (moved, spp) = match backend {
        Backend::Cpu => (
            render.spp(POWERFUL_SPP).seed(seed).cpu_shared(),
            POWERFUL_SPP,
        ),
        Backend::Gpu => (
            std::sync::Arc::new(render.spp(GPU_SPP).seed(seed + 100).gpu()),
            GPU_SPP,
        ),
    };
    let p = parity(&room_reference(), &moved);
    eprintln!("{backend} {name} at {spp} spp against the CPU room: {p}");
    p
}

fn assert_same(backend: Backend, name: &str) {
    let p = moved_parity(backend, name, Faults::NONE);
    assert!(p.same(), "{backend} {name} differs from the room: {p}");
}

on_each_backend! {
    fn room_translated_by_1e3_renders_the_same_image(backend) {
        assert_same(backend, "translated_1e3");
    }

    fn room_translated_by_1e4_renders_the_same_image(backend) {
        assert_same(backend, "translated_1e4");
    }

    fn room_translated_by_1e5_renders_the_same_image(backend) {
        assert_same(backend, "translated_1e5");
    }

    fn room_scaled_by_1e_minus_3_renders_the_same_image(backend) {
        assert_same(backend, "scaled_1e-3");
    }

    fn room_scaled_by_1e3_renders_the_same_image(backend) {
        assert_same(backend, "scaled_1e3");
    }

    /// BDPT far from the origin: the room moved to 1e5 renders, with BDPT, the image the room
    /// renders with path tracing at the origin (the same parity statistic; BDPT's block
    /// variances are checked in tests/standard_error.rs). Its connections and splats spawn rays
    /// at both ends of every edge, and its MIS densities hold squared distances: both must
    /// survive the move. The CPU renders 512 iterations (seed + 200), the GPU 128 (seed + 300).
    fn bdpt_room_translated_by_1e5_renders_the_same_image(backend) {
        let (rel, seed) = scene("translated_1e5");
        let (iterations, seed) = match backend {
            Backend::Cpu => (512, seed + 200),
            Backend::Gpu => (128, seed + 300),
        };
        let moved = Render::file(&rel)
            .size(SIZE, SIZE)
            .spp(iterations)
            .seed(seed)
            .method(hexray::transport::method::Method::Bdpt)
            .on(backend);
        let p = parity(&room_reference(), &moved);
        eprintln!(
            "{backend} BDPT translated_1e5 at {iterations} iterations against the CPU room: {p}"
        );
        assert!(p.same(), "{backend} BDPT at 1e5 differs from the room: {p}");
    }
}

/// Power: the room translated by 1e5, against the untranslated room rendered with mirrors
/// (and glass reflections) scaled by 0.97, at the same spp, is rejected.
#[test]
fn far_from_origin_parity_rejects_a_mirror_3_percent_too_dark() {
    let (rel, seed) = scene("translated_1e5");
    let moved = Render::file(&rel)
        .size(SIZE, SIZE)
        .spp(POWERFUL_SPP)
        .seed(seed)
        .cpu_shared();
    let p = parity(&dark_mirror_room(), &moved);
    eprintln!("translated_1e5 against a room with 3 % dark mirrors: {p}");
    assert!(!p.same(), "a 3 % dark mirror passed: {p}");
}

/// Power of the GPU's test at its spp: a GPU whose mirrors reflect 92 % is rejected.
#[test]
fn far_from_origin_gpu_parity_rejects_a_gpu_mirror_8_percent_too_dark() {
    let dark = Faults {
        specular_scale: 0.92,
        ..Faults::NONE
    };
    if gpu().is_none() {
        return;
    }
    let p = moved_parity(Backend::Gpu, "translated_1e5", dark);
    assert!(!p.same(), "an 8 % dark GPU mirror passed: {p}");
}

/// Where f32 ends: the same statistics at 1e6 and 1e7 (the numbers in the issue report). Not run
/// by default (four more renders); `cargo test --release stability_far -- --ignored`. Both
/// translations are rejected on both backends: at 1e6 the light (z = 4.99, 0.01 under the
/// ceiling) rounds onto the ceiling's plane (ulp 0.0625) and the spawned rays start 0.42 off the
/// surfaces (the hit point's error bound γ7 Σ|b p| ≈ 4.2e-7 x 1e6); at 1e7 (ulp 1) the sphere's
/// centre moves by half a unit into the floor and the offsets are 4 units.
#[test]
#[ignore]
fn where_f32_ends_1e6_and_1e7_are_rejected() {
    for name in ["translated_1e6", "translated_1e7"] {
        let p = moved_parity(Backend::Cpu, name, Faults::NONE);
        let g = gpu().map(|_| moved_parity(Backend::Gpu, name, Faults::NONE));
        self_hits(&scene(name).0, offset_ray_origin);
        assert!(!p.same(), "CPU {name} passed: {p}");
        if let Some(g) = g {
            assert!(!g.same(), "GPU {name} passed: {g}");
        }
    }
}

/// The paired measurement behind the report's decomposition of the bias (not a default test:
/// `-- --ignored`): each camera sample's path is traced with the same random numbers in two
/// scenes, so the per-sample differences have a far smaller variance than two independent
/// renders, and their mean is compared with its own s.e. Printed: the translated room against the
/// room, the room with its coordinates rounded as f32 at the translation and moved back (what
/// the renderer is given, rendered where f32 is fine) against the room (the geometric part), and
/// the translated room against that rounded room (the arithmetic part). Asserted: at 1e4 no
/// bias (|z| ≤ 4 per channel), at 1e5 a bias below 0.5 %. Several minutes on 2 cores.
#[test]
#[ignore]
fn paired_bias_far_from_origin() {
    use hexray::layout::FlatScene;
    let (room, room_flat) = load(ROOM);
    let rounded = |k: i32| {
        let t = 10f64.powi(k);
        let r = |x: f64| ((x + t) as f32) as f64 - t;
        let mut desc = room.desc.clone();
        for tri in &mut desc.triangles {
            tri.v = tri.v.map(|v| v.map(r));
        }
        for s in &mut desc.spheres {
            s.center = s.center.map(r);
        }
        let scene = hexray::scene::Scene {
            desc,
            ..room.clone()
        };
        let flat = FlatScene::build(&scene, hexray::render::CpuBackend::TRAVERSAL);
        (scene, flat)
    };
    let paired = |a: &(hexray::scene::Scene, FlatScene),
                  b: &(hexray::scene::Scene, FlatScene),
                  spp: u32| {
        let (ca, cb) = (
            Camera::new(&a.0.desc.camera, SIZE, SIZE),
            Camera::new(&b.0.desc.camera, SIZE, SIZE),
        );
        let sums: Vec<[[f64; 3]; 3]> = (0..SIZE * SIZE)
            .into_par_iter()
            .map(|p| {
                let mut acc = [[0.0; 3]; 3];
                let mut rays = 0;
                for s in 0..spp {
                    let smp = Sampler::new(7, p, s);
                    let (x, y) = (p % SIZE, p / SIZE);
                    let la =
                        hexray::cpu::trace_path(&a.1, &ca, x, y, &smp, 1, Faults::NONE, &mut rays);
                    let lb =
                        hexray::cpu::trace_path(&b.1, &cb, x, y, &smp, 1, Faults::NONE, &mut rays);
                    for c in 0..3 {
                        let d = (lb[c] - la[c]) as f64;
                        acc[0][c] += d;
                        acc[1][c] += d * d;
                        acc[2][c] += la[c] as f64;
                    }
                }
                acc
            })
            .collect();
        let n = (SIZE * SIZE * spp) as f64;
        [0, 1, 2].map(|c| {
            let (d, d2, m) = sums.iter().fold((0.0, 0.0, 0.0), |(x, y, z), a| {
                (x + a[0][c], y + a[1][c], z + a[2][c])
            });
            let (md, mean) = (d / n, m / n);
            let se = ((d2 / n - md * md) / (n - 1.0)).sqrt();
            (md / mean, se / mean)
        })
    };
    let show = |what: &str, r: [(f64, f64); 3]| {
        eprintln!(
            "{what}: {:+.3} % ± {:.3}, {:+.3} % ± {:.3}, {:+.3} % ± {:.3}",
            100.0 * r[0].0,
            100.0 * r[0].1,
            100.0 * r[1].0,
            100.0 * r[1].1,
            100.0 * r[2].0,
            100.0 * r[2].1
        );
        r
    };
    let base = (room.clone(), room_flat);
    for k in 4..=7 {
        // 1e5's bias is a few tenths of a percent: 8192 paired samples per pixel resolve it.
        let spp = if k == 5 { 8192 } else { 1024 };
        let moved = load(&scene_path(k));
        let q = rounded(k);
        let total = show(
            &format!("1e{k} against the room"),
            paired(&base, &moved, spp),
        );
        show(
            &format!("1e{k}: f32-rounded room against the room"),
            paired(&base, &q, spp),
        );
        show(
            &format!("1e{k} against the f32-rounded room"),
            paired(&q, &moved, spp),
        );
        if k == 4 {
            assert!(total.iter().all(|(d, se)| (d / se).abs() <= 4.0));
        }
        if k == 5 {
            assert!(total.iter().all(|(d, _)| d.abs() < 0.005));
        }
    }
}

fn scene_path(k: i32) -> String {
    format!("scenes/stability/tncg15_translated_1e{k}.json")
}

/// How a spawned ray's origin is chosen from the hit point, its error bound, its normal and the
/// direction.
type Spawn = fn(Vec3, Vec3, Vec3, Vec3) -> Vec3;

/// The planted error: rays start at the hit point itself.
fn no_offset(p: Vec3, _p_err: Vec3, _n: Vec3, _w: Vec3) -> Vec3 {
    p
}

/// Vertices per path (the camera ray's hit and three more).
const VERTICES: u32 = 4;
/// Camera paths per pixel, over 64x64 pixels, for the self-intersection count.
const PATHS_PER_PIXEL: u32 = 64;
const HIT_SIZE: u32 = 64;

/// (spawned rays, self-hits) over camera paths of a scene.
fn self_hits(rel: &str, spawn: Spawn) -> (u64, u64) {
    let (scene, flat) = load(rel);
    let camera = Camera::new(&scene.desc.camera, HIT_SIZE, HIT_SIZE);
    let leaves_again = |hit: &SurfaceHit, w: Vec3| -> bool {
        let ray = Ray {
            o: spawn(hit.p, hit.p_err, hit.n, w),
            d: w,
        };
        if hit.prim & PRIM_SPHERE_BIT == 0 {
            intersect_triangle(&ray, &flat.triangles[hit.prim as usize]).is_some()
        } else {
            let s = &flat.spheres[(hit.prim & !PRIM_SPHERE_BIT) as usize];
            let cos = w.dot(hit.n);
            match intersect_sphere(&ray, s) {
                // Outward: nothing to hit. Inward: the far side, a chord 2 r |cos| away.
                Some(_) if cos > 0.0 => true,
                Some(h) => h.t <= s.radius * -cos,
                None => false,
            }
        }
    };
    let counts: Vec<(u64, u64)> = (0..HIT_SIZE * HIT_SIZE)
        .into_par_iter()
        .map(|pixel| {
            let (mut spawned, mut again) = (0u64, 0u64);
            for sample in 0..PATHS_PER_PIXEL {
                let s = Sampler::new(31, pixel, sample);
                let u = s.draw4(DIM_CAMERA);
                let mut ray = camera.ray(pixel % HIT_SIZE, pixel / HIT_SIZE, u[0], u[1]);
                for bounce in 0..VERTICES {
                    let Some(hit) = intersect_closest(&flat, &ray, f32::MAX) else {
                        break;
                    };
                    let m = flat.materials[hit.material as usize];
                    if m.kind == KIND_EMITTER {
                        break;
                    }
                    if m.kind == KIND_DIFFUSE {
                        let ul = s.draw4(dim_light(bounce));
                        let ls = sample_emitter(&flat, ul[0], ul[1], ul[2]);
                        let wi = (ls.p - hit.p).normalize();
                        spawned += 1;
                        again += leaves_again(&hit, wi) as u64;
                    }
                    let bs = sample_bsdf(
                        &m,
                        hit.n,
                        -ray.d,
                        s.draw4(dim_bsdf(bounce)),
                        Transport::Radiance,
                    );
                    spawned += 1;
                    again += leaves_again(&hit, bs.wi) as u64;
                    ray = Ray {
                        o: spawn(hit.p, hit.p_err, hit.n, bs.wi),
                        d: bs.wi,
                    };
                }
            }
            (spawned, again)
        })
        .collect();
    let (spawned, again) = counts.iter().fold((0, 0), |(a, b), (c, d)| (a + c, b + d));
    eprintln!(
        "{rel}: {again} self-hits in {spawned} spawned rays ({:.1} per million)",
        again as f64 * 1e6 / spawned as f64
    );
    (spawned, again)
}

#[test]
fn rays_spawned_at_path_vertices_never_hit_their_own_surface_far_from_origin() {
    let mut failed = Vec::new();
    for rel in std::iter::once(ROOM.to_string()).chain(
        [
            "translated_1e3",
            "translated_1e4",
            "translated_1e5",
            "scaled_1e-3",
            "scaled_1e3",
        ]
        .map(|n| scene(n).0),
    ) {
        let (spawned, again) = self_hits(&rel, offset_ray_origin);
        assert!(spawned > 1_000_000, "{rel}: only {spawned} rays spawned");
        if again > 0 {
            failed.push(format!("{rel}: {again} of {spawned}"));
        }
    }
    assert!(failed.is_empty(), "self-hits: {failed:?}");
}

/// Power: without the offset, rays spawned at the same vertices do hit their own surface.
#[test]
fn self_hit_count_catches_rays_spawned_without_offset() {
    let (rel, _) = scene("translated_1e5");
    let (spawned, again) = self_hits(&rel, no_offset);
    assert!(
        again > 0,
        "without the offset none of {spawned} rays hit their own surface"
    );
}
