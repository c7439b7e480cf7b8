//! Nanoseconds a ray, one by one against eight to a packet (`src/accel/packet.rs`), on the rays a
//! path tracer's second bounce traces: from each pixel's first hit, a cosine-distributed
//! closest-hit ray and a shadow ray to a point on an emitter (docs/journal/2026-11-26_packets.md, "Ray packets
//! over a wavefront of paths"). One thread, the best of five timings of each.
//!
//! ```sh
//! cargo run --release --example packet_rays [SCENE.json ...]
//! ```
//!
//! Default: the three reference scenes. On a large tree (`packet::LARGE_TREE_NODES`; the
//! tessellated rooms and the bunny of `scenes/perf/`) a packet visits children nearest first and
//! hands rays that part ways to single-ray traversal, which this measures too.

use hexray::accel::bvh::{intersect_closest, occluded};
use hexray::accel::packet::{intersect_closest_packets, occluded_all};
use hexray::layout::FlatScene;
use hexray::math::geometry::{offset_ray_origin, Ray};
use hexray::math::sampling::{orthonormal_basis, pcg4d, sample_cosine_hemisphere, u32_to_unit_f32};
use hexray::transport::camera::Camera;
use hexray::transport::light::sample_emitter;
use std::time::Instant;

mod common;

const SIZE: u32 = 256;

/// Number `k` of pixel `i`'s test data, uniform in [0, 1).
fn rnd(i: u32, k: u32) -> f32 {
    u32_to_unit_f32(pcg4d([i, k, 17, 29])[0])
}

/// The best of five timings of `f`, in seconds.
fn best_of_five(mut f: impl FnMut()) -> f64 {
    (0..5)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let args = common::scene_paths(std::env::args().skip(1).collect());
    println!("{SIZE}x{SIZE} pixels' second-bounce rays, one thread, ns a ray (best of 5)");
    println!("scene                four-wide nodes  closest: one  packet  ratio   shadow: one  packet  ratio");
    for path in &args {
        let scene = common::load(path);
        let flat = FlatScene::build(&scene, hexray::render::CpuBackend::TRAVERSAL);
        let camera = Camera::new(&scene.desc.camera, SIZE, SIZE);
        let (mut bounce, mut shadow) = (Vec::new(), Vec::new());
        for i in 0..SIZE * SIZE {
            let ray = camera.ray(i % SIZE, i / SIZE, rnd(i, 0), rnd(i, 1));
            let Some(hit) = intersect_closest(&flat, &ray, f32::MAX) else {
                continue;
            };
            let n = if hit.n.dot(ray.d) > 0.0 {
                -hit.n
            } else {
                hit.n
            };
            let local = sample_cosine_hemisphere(rnd(i, 2), rnd(i, 3));
            let (t, b) = orthonormal_basis(n);
            let d = local.x * t + local.y * b + local.z * n;
            bounce.push(Ray {
                o: offset_ray_origin(hit.p, hit.p_err, hit.n, d),
                d,
            });
            let ls = sample_emitter(&flat, rnd(i, 4), rnd(i, 5), rnd(i, 6));
            let to_light = ls.p - hit.p;
            let o = offset_ray_origin(hit.p, hit.p_err, hit.n, to_light);
            let end = offset_ray_origin(ls.p, ls.p_err, ls.n, -to_light);
            shadow.push(Ray { o, d: end - o });
        }
        let mut hits = vec![None; bounce.len()];
        let closest_one = best_of_five(|| {
            for (r, h) in bounce.iter().zip(hits.iter_mut()) {
                *h = intersect_closest(&flat, r, f32::MAX);
            }
        });
        let closest_packet = best_of_five(|| intersect_closest_packets(&flat, &bounce, &mut hits));
        let mut blocked = vec![false; shadow.len()];
        let shadow_one = best_of_five(|| {
            for (r, b) in shadow.iter().zip(blocked.iter_mut()) {
                *b = occluded(&flat, r, 1.0);
            }
        });
        let shadow_packet = best_of_five(|| occluded_all(&flat, &shadow, &mut blocked));
        let ns = |s: f64, n: usize| s * 1e9 / n as f64;
        let name = common::name(path);
        println!(
            "{name:<20} {:>15} {:>13.1} {:>7.1} {:>6.2} {:>13.1} {:>7.1} {:>6.2}",
            flat.nodes.len(),
            ns(closest_one, bounce.len()),
            ns(closest_packet, bounce.len()),
            closest_packet / closest_one,
            ns(shadow_one, shadow.len()),
            ns(shadow_packet, shadow.len()),
            shadow_packet / shadow_one,
        );
    }
}
