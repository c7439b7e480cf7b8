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
use hexray::film::Film;
use hexray::transport::faults::Faults;

const ROOM: &str = "scenes/tncg15_room.json";
const TESSELLATED: &str = "scenes/perf/tncg15_room_x100.json";

fn room(seed: u32) -> Film {
    Render::file(ROOM).size(32, 32).spp(1024).seed(seed).cpu()
}

on_each_backend! {
    /// The tessellated room on `backend` against the room on the CPU (1024 spp, seed 61),
    /// at 1024 spp with seed 62 on the CPU, 256 with seed 64 on the GPU (the room then seed 63).
    fn tessellated_room_renders_the_room(backend) {
        let (room_seed, spp, seed) = match backend {
            Backend::Cpu => (61, 1024, 62),
            Backend::Gpu => (63, 256, 64),
        };
        let room = room(room_seed);
        let fine = Render::file(TESSELLATED)
            .size(32, 32)
            .spp(spp)
            .seed(seed)
            .on(backend);
        let p = parity(&room, &fine);
        eprintln!("x100 on the {backend} vs room on the CPU: {p}");
        assert!(p.same(), "{p}");
    }
}

#[test]
fn tessellation_test_rejects_mirrors_3_percent_too_dark() {
    let room = room(61);
    let dim = Faults {
        specular_scale: 0.97,
        ..Faults::NONE
    };
    let fine = Render::file(TESSELLATED)
        .size(32, 32)
        .spp(1024)
        .seed(62)
        .faults(dim)
        .cpu();
    let p = parity(&room, &fine);
    eprintln!("x100 with dim mirrors vs room, CPU: {p}");
    assert!(!p.same(), "dim mirrors passed: {p}");
}
