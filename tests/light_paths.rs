//! The light subpaths per iteration N (`hexray::transport::merging::light_paths`).
//! With fewer than one per pixel the camera subpaths share them (pixel index mod N), and the
//! kernel's normalisation, the splats and the MIS weights count N: the image is the one of one
//! light subpath per pixel, only noisier. Each comparison is of two independent renders (other
//! seeds) by their iterations' batch means (`parity_of_iterations`), and is shown to reject
//! counting one light subpath per pixel where N were traced.

use crate::common::parity::{parity_of_iterations, Parity};
use crate::common::*;
use hexray::transport::faults::Faults;
use hexray::transport::method::Method;

const ROOM: &str = "scenes/tncg15_room.json";

/// Image side and iterations of every render here.
const SIZE: u32 = 32;
const ITERATIONS: u32 = 64;

/// A quarter of the image's pixels: each light subpath is shared by four camera subpaths.
const QUARTER: u32 = SIZE * SIZE / 4;

/// `method`'s iterations of tncg15_room on `backend` with N = `light_paths` (None: one per
/// pixel).
fn iterations(
    backend: Backend,
    method: Method,
    seed: u32,
    light_paths: Option<u32>,
    faults: Faults,
) -> Vec<hexray::film::Film> {
    let mut radius = default_radius(ROOM, method);
    radius.light_paths = light_paths;
    Render::file(ROOM)
        .size(SIZE, SIZE)
        .spp(ITERATIONS)
        .seed(seed)
        .method(method)
        .radius(radius)
        .faults(faults)
        .iterations_on(backend)
}

/// One light subpath per pixel against a quarter as many (with `faults`).
fn quarter_parity(backend: Backend, method: Method, faults: Faults) -> Parity {
    let a = iterations(backend, method, 51, None, Faults::NONE);
    let b = iterations(backend, method, 52, Some(QUARTER), faults);
    let p = parity_of_iterations(&a, &b);
    eprintln!("{method}, N = pixels against N = pixels / 4 ({backend:?}): {p}");
    p
}

on_each_backend! {
    /// vcm's image of tncg15_room with a quarter as many light subpaths as pixels is the image
    /// with one per pixel.
    fn fewer_light_subpaths_than_pixels_leave_the_vcm_image_unchanged(backend) {
        let p = quarter_parity(backend, Method::Vcm, Faults::NONE);
        assert!(p.same(), "{p}");
    }

    /// So is sppm's, whose image is all merges.
    fn fewer_light_subpaths_than_pixels_leave_the_sppm_image_unchanged(backend) {
        let p = quarter_parity(backend, Method::Sppm, Faults::NONE);
        assert!(p.same(), "{p}");
    }

    /// So is bdpt's, whose camera subpaths connect to shared light subpaths.
    fn fewer_light_subpaths_than_pixels_leave_the_bdpt_image_unchanged(backend) {
        let p = quarter_parity(backend, Method::Bdpt, Faults::NONE);
        assert!(p.same(), "{p}");
    }

    /// So is light tracing's, whose image is all splats.
    fn fewer_light_subpaths_than_pixels_leave_the_light_tracing_image_unchanged(backend) {
        let p = quarter_parity(backend, Method::Light, Faults::NONE);
        assert!(p.same(), "{p}");
    }
}

/// The comparison has power: counting one light subpath per pixel where a quarter as many were
/// traced divides the merges and the splats by four times too much.
#[test]
fn the_light_subpath_check_rejects_counting_one_per_pixel() {
    let fault = Faults {
        light_paths_counted_per_pixel: true,
        ..Faults::NONE
    };
    let p = quarter_parity(Backend::Cpu, Method::Sppm, fault);
    assert!(!p.same(), "{p}");
}
