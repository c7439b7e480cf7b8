//! The same surfaces in 100 times as many triangles render the same image: `tncg15_room` with
//! every triangle split into 100 coplanar ones of the same winding
//! (`scenes/perf/tncg15_room_x100.json`, the benchmark's cost-growth scene) against the room
//! itself. It checks the BVH and the intersection at 2600 triangles (a deeper four-wide tree,
//! storage buffers on lavapipe) and the shared edges the tessellation adds: a crack along them
//! lets rays out of the room (black samples), a self-hit on a neighbouring coplanar triangle
//! darkens the image.
//!
//! Statistic: `tests/gpu_parity.rs`'s (per 8x8 block and channel Welch's t with Bonferroni at
//! α = 0.01 overall, and the image-mean ratio within 4 s.e. of 1) between independent renders
//! (other seeds), 32x32 pixels: 1024 spp on the CPU, 256 on the GPU against the CPU's room.
//! Power: the same comparison rejects the tessellated room with mirrors 3 % too dark.

use crate::common::parity::parity;
use crate::common::*;
use hexray::transport::faults::Faults;

const ROOM: &str = "scenes/tncg15_room.json";
const TESSELLATED: &str = "scenes/perf/tncg15_room_x100.json";

#[test]
fn tessellated_room_renders_the_room_on_the_cpu() {
    let room = render_cpu(ROOM, 32, 32, 1024, 61, Faults::NONE);
    let fine = render_cpu(TESSELLATED, 32, 32, 1024, 62, Faults::NONE);
    let p = parity(&room, &fine);
    eprintln!("x100 vs room, CPU: {p}");
    assert!(p.same(), "{p}");
}

#[test]
fn tessellated_room_renders_the_room_on_the_gpu() {
    let Some(gpu) = gpu() else { return };
    let room = render_cpu(ROOM, 32, 32, 1024, 63, Faults::NONE);
    let fine = render_gpu(gpu, TESSELLATED, 32, 32, 256, 64, Faults::NONE);
    let p = parity(&room, &fine);
    eprintln!("x100 on the GPU vs room on the CPU: {p}");
    assert!(p.same(), "{p}");
}

#[test]
fn tessellation_test_rejects_mirrors_3_percent_too_dark() {
    let room = render_cpu(ROOM, 32, 32, 1024, 61, Faults::NONE);
    let dim = Faults {
        specular_scale: 0.97,
        ..Faults::NONE
    };
    let fine = render_cpu(TESSELLATED, 32, 32, 1024, 62, dim);
    let p = parity(&room, &fine);
    eprintln!("x100 with dim mirrors vs room, CPU: {p}");
    assert!(!p.same(), "dim mirrors passed: {p}");
}
