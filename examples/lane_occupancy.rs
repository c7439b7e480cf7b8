//! How busy SIMD lanes stay when a GPU runs `shaders/path.wgsl` in lockstep: a measurement of
//! the work itself, not of a clock (where lavapipe's SIMD lanes idle).
//!
//! ```sh
//! cargo run --release --features counters --example lane_occupancy [LANES] [SCENE.json ...]
//! ```
//!
//! A GPU, and lavapipe with its 8 lanes of 32 bits in 256-bit registers, runs a group of
//! invocations in lockstep: a loop turns as long as one lane needs it, and the other lanes wait
//! masked. `render_pass` in `shaders/path.wgsl` is one invocation per pixel of an 8x8 workgroup, so a
//! group is LANES (default 8) neighbouring pixels of one row and one sample. This traces the
//! same paths on the CPU (same streams: the GPU's paths are these, ray for ray), counts per ray
//! the BVH nodes visited and the primitives tested (the units of `shaders/bvh.wgsl`'s loops,
//! feature `counters`) and reports, per scene:
//!
//! - bounce occupancy: loop turns of the path (bounces) done over LANES x the turns the group
//!   takes (the longest path's);
//! - traversal occupancy: nodes + primitives of all rays over LANES x what lockstep costs,
//!   bounce by bounce the most any lane needs for its closest-hit ray plus the most any lane
//!   needs for its shadow ray. This is an upper bound: inside one traversal the lanes diverge
//!   further (a leaf here, a node there), which the per-ray totals do not see.

use hexray::accel::bvh::counters::{self, Work};
use hexray::cpu::trace_path;
use hexray::layout::FlatScene;
use hexray::math::sampling::Sampler;
use hexray::transport::camera::Camera;
use hexray::transport::faults::Faults;

mod common;

const SIZE: u32 = 256;
const SAMPLES: u32 = 16;
const SEED: u32 = 1;

/// One path's rays, bounce by bounce: (closest-hit work, shadow-ray work or 0).
fn bounces(rays: &[Work]) -> Vec<(u32, u32)> {
    let mut out: Vec<(u32, u32)> = Vec::new();
    for w in rays {
        let steps = w.nodes + w.primitives;
        match (w.shadow, out.last_mut()) {
            (true, Some(last)) => last.1 += steps,
            _ => out.push((steps, 0)),
        }
    }
    out
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let lanes: usize = match args.first().and_then(|a| a.parse().ok()) {
        Some(n) => {
            args.remove(0);
            n
        }
        None => 8,
    };
    args = common::scene_paths(args);
    println!("{SIZE}x{SIZE}, {SAMPLES} samples, groups of {lanes} neighbouring pixels of a row");
    println!(
        "scene            samples  bounces/path  max in group  bounce occupancy  steps/ray  traversal occupancy"
    );
    println!("                 a lane");
    for path in &args {
        let scene = common::load(path);
        let mut flat = FlatScene::build(&scene, hexray::gpu::GpuRenderer::TRAVERSAL);
        // The shader traverses the four-wide tree: count its nodes, not the CPU's wide ones.
        flat.wide = hexray::accel::wide_bvh::one_for_one(&flat.nodes);
        let camera = Camera::new(&scene.desc.camera, SIZE, SIZE);
        // Every pixel's paths, bounce by bounce, sample after sample.
        let paths: Vec<Vec<Vec<(u32, u32)>>> = (0..SIZE * SIZE)
            .map(|index| {
                let (x, y) = (index % SIZE, index / SIZE);
                (0..SAMPLES)
                    .map(|s| {
                        let sampler = Sampler::new(SEED, index, s);
                        let mut n = 0;
                        counters::take();
                        trace_path(&flat, &camera, x, y, &sampler, 1, Faults::NONE, &mut n);
                        bounces(&counters::take())
                    })
                    .collect()
            })
            .collect();
        let name = common::name(path);
        for per_lane in [1, SAMPLES] {
            let o = occupancy(&paths, lanes, per_lane as usize);
            println!(
                "{name:<16} {per_lane:>7} {:>12.2} {:>13.2} {:>17.3} {:>10.1} {:>20.3}",
                o.bounces_per_path, o.longest, o.bounce, o.steps_per_ray, o.traversal
            );
        }
    }
}

struct Occupancy {
    bounces_per_path: f64,
    /// The mean over groups of the longest lane's bounces.
    longest: f64,
    bounce: f64,
    steps_per_ray: f64,
    traversal: f64,
}

/// Lanes of `lanes` neighbouring pixels of a row, each lane running `per_lane` samples of its
/// pixel one after the other without waiting for the group (path regeneration) when
/// `per_lane` > 1, or one sample a group when 1.
fn occupancy(paths: &[Vec<Vec<(u32, u32)>>], lanes: usize, per_lane: usize) -> Occupancy {
    let (mut turns_done, mut turns_lockstep) = (0u64, 0u64);
    let (mut steps_done, mut steps_lockstep) = (0u64, 0u64);
    let (mut n_paths, mut rays, mut groups) = (0u64, 0u64, 0u64);
    for row in paths.chunks(SIZE as usize) {
        for pixels in row.chunks(lanes) {
            for first in (0..SAMPLES as usize).step_by(per_lane) {
                // Each lane's bounces, its samples first..first + per_lane in turn.
                let group: Vec<Vec<(u32, u32)>> = pixels
                    .iter()
                    .map(|p| p[first..first + per_lane].concat())
                    .collect();
                let longest = group.iter().map(Vec::len).max().unwrap_or(0);
                for p in &group {
                    rays += p.iter().map(|b| 1 + u64::from(b.1 > 0)).sum::<u64>();
                    turns_done += p.len() as u64;
                    steps_done += p.iter().map(|b| u64::from(b.0 + b.1)).sum::<u64>();
                }
                n_paths += (pixels.len() * per_lane) as u64;
                turns_lockstep += longest as u64;
                groups += 1;
                for b in 0..longest {
                    let closest = group.iter().filter_map(|p| p.get(b)).map(|b| b.0);
                    let shadow = group.iter().filter_map(|p| p.get(b)).map(|b| b.1);
                    steps_lockstep +=
                        u64::from(closest.max().unwrap_or(0) + shadow.max().unwrap_or(0));
                }
            }
        }
    }
    Occupancy {
        bounces_per_path: turns_done as f64 / n_paths as f64,
        longest: turns_lockstep as f64 / groups as f64,
        bounce: turns_done as f64 / (lanes as f64 * turns_lockstep as f64),
        steps_per_ray: steps_done as f64 / rays as f64,
        traversal: steps_done as f64 / (lanes as f64 * steps_lockstep as f64),
    }
}
