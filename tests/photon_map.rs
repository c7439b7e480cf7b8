//! Photon mapping in Jensen's two-pass form (`--method photon-map`, `src/cpu/photon_map.rs`,
//! `shaders/photon_map.wgsl`), property by property. Its density estimates are biased at any
//! radius, so these check where the estimate is exact (the sphere furnace), convergence as the
//! radius shrinks and the photons grow, and the GPU against the CPU on the same random streams.
//!
//! Planted by hand on 2026-11-29, each rejected by the sphere furnace (CPU, seed 21, 256
//! iterations, s.e. 1.9e-4 when correct):
//! - the global map also gathered at x (`src/cpu/photon_map.rs`; light counted twice): mean
//!   1.2503 (z 272);
//! - the light's first hits stored too (`src/cpu/light_path.rs`; they join the caustic map, so
//!   direct light is counted twice at x and at y): mean 1.3745 (z 312).

use crate::common::*;
use crate::photon_merging::{
    merging_furnace, relmse, same_streams_at, BALL, CAUSTIC, CAUSTIC_REFERENCE,
    FLIPPED_PIXELS_ALLOWED, SAME_STREAMS_RADIUS,
};
use hexray::film::Film;
use hexray::transport::faults::Faults;
use hexray::transport::merging::{scene_radius, MergeRadius};
use hexray::transport::method::Method;

on_each_backend! {
    /// The merging furnace (`photon_merging.rs`: inside an emitting sphere, L = 1 everywhere,
    /// and the sphere within r of any point is a cap of area exactly π r²) is where a density
    /// estimate is exact at any radius: next-event estimation, the caustic map (empty here) and
    /// final gathering into the global map add up to 1 within 4 s.e. The sum checks the split:
    /// light counted by two of the parts, or by none, moves it.
    fn photon_map_in_the_merging_furnace_is_exactly_1(backend) {
        let film = merging_furnace(backend, Method::PhotonMap, Faults::NONE);
        assert_mean_within_4_se(&film, [1.0; 3], &format!("{backend} photon-map in the merging furnace"));
    }

    /// The furnace check has power: the 3-D ball's normalisation 1 / (4/3 π r³) instead of the
    /// disk's scales the global map's estimate by 3 / (4r) = 7.5.
    fn the_photon_map_furnace_rejects_a_ball_kernel(backend) {
        let film = merging_furnace(backend, Method::PhotonMap, BALL);
        let (mean, _, z) = image_mean_z(&film, [1.0; 3]);
        eprintln!("{backend} photon-map with a ball kernel: mean {:.4}, z {:.1}", mean[0], z[0]);
        assert!(z.iter().all(|z| z.abs() > 4.0), "{backend}: z {z:?}");
    }
}

/// photon-map's image of the caustic scene (a glass sphere focusing a small light onto the
/// floor, whose light reaches the floor only through the caustic map) at 32x32: `n`
/// iterations, each with `photons` light subpaths, within `share` of the default radius.
fn caustic(share: f32, photons: u32, n: u32, seed: u32, faults: Faults) -> Film {
    let base = default_radius(CAUSTIC, Method::PhotonMap);
    let radius = MergeRadius {
        initial: base.initial * share,
        light_paths: Some(photons),
        ..base
    };
    Render::file(CAUSTIC)
        .size(32, 32)
        .spp(n)
        .seed(seed)
        .method(Method::PhotonMap)
        .radius(radius)
        .faults(faults)
        .cpu()
}

/// Convergence to the path-traced reference (32x32, 65536 spp) as the photons grow and the
/// radius shrinks: with 4x the photons an iteration, 4x the iterations and half the radius,
/// the relMSE (the reference's noise subtracted) falls to at most half: measured 3.6e-2 ->
/// 8.5e-3, and the image mean is then within 1.3 s.e. of the reference's.
#[test]
fn photon_map_converges_on_the_caustic_as_photons_grow_and_the_radius_shrinks() {
    let truth = crate::common::reference::read(CAUSTIC_REFERENCE);
    let coarse = caustic(2.0, 256, 64, 31, Faults::NONE);
    let fine = caustic(1.0, 1024, 256, 32, Faults::NONE);
    let (e_coarse, e_fine) = (relmse(&coarse, &truth), relmse(&fine, &truth));
    eprintln!("photon-map on the caustic: relMSE {e_coarse:.3e} (2r, 256 photons, 64 iterations) -> {e_fine:.3e} (r, 1024, 256)");
    assert!(
        e_fine <= 0.5 * e_coarse,
        "relMSE {e_coarse:e} -> {e_fine:e}"
    );
    let z = crate::common::reference::film_mean_z(
        "photon-map, r, 1024 photons",
        &fine,
        CAUSTIC_REFERENCE,
    );
    assert!(crate::common::reference::means_agree(z), "z {z:?}");
}

/// The convergence check has power: glass that passes 90 % of the light dims the caustic,
/// and the fine render's image mean is far from the reference's.
#[test]
fn the_photon_map_convergence_check_rejects_glass_10_percent_too_dark() {
    let dark = Faults {
        specular_scale: 0.9,
        ..Faults::NONE
    };
    let film = caustic(1.0, 1024, 256, 32, dark);
    let z =
        crate::common::reference::film_mean_z("photon-map, dark glass", &film, CAUSTIC_REFERENCE);
    assert!(!crate::common::reference::means_agree(z), "z {z:?}");
}

/// The GPU's photon-map against the CPU's on the same streams (64x64, 16 iterations, seed 7,
/// a fixed radius of 0.01 of the scene radius): pixels whose photons sit on a disk's edge may
/// flip with a rounding, as in the other merging methods (`photon_merging.rs`), so the count of
/// pixels beyond a relative 1e-4 is held to the same allowance.
fn same_streams(rel: &str, gpu_faults: Faults) -> Option<usize> {
    let (_, flat) = load(rel);
    let radius = MergeRadius::uniform(SAME_STREAMS_RADIUS * scene_radius(&flat), 1.0);
    same_streams_at(rel, Method::PhotonMap, radius, gpu_faults)
}

#[test]
fn gpu_photon_map_equals_cpu_on_the_same_streams() {
    for rel in ["scenes/tncg15_room.json", "scenes/glass_room.json"] {
        if let Some(n) = same_streams(rel, Faults::NONE) {
            assert!(n <= FLIPPED_PIXELS_ALLOWED, "{rel}: {n} pixels differ");
        }
    }
}

/// The same-streams check has power: a GPU whose mirrors and glass pass 97 % is rejected.
#[test]
fn the_photon_map_same_streams_check_rejects_a_gpu_mirror_3_percent_too_dark() {
    let dim = Faults {
        specular_scale: 0.97,
        ..Faults::NONE
    };
    if let Some(n) = same_streams("scenes/tncg15_room.json", dim) {
        assert!(n > FLIPPED_PIXELS_ALLOWED, "{n} pixels differ");
    }
}

/// A photon-map render says that it is biased and by what radius, in its summary line and in
/// its EXR metadata (a fixed radius: alpha 1), and refuses --alpha before any work (exit 2).
#[test]
fn a_photon_map_render_says_its_radius_is_fixed_and_refuses_alpha() {
    let dir = empty_temp_dir("photon-map-bias");
    let exr = dir.join("p.exr");
    let render =
        |extra: &[&str]| small_cli_render("scenes/tncg15_room.json", "photon-map", extra, &exr);
    let o = render(&[]);
    let log = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{log}");
    assert!(log.contains("photon-map is biased"), "{log}");
    let (_, meta) = hexray::film::output::read_exr(&exr).unwrap();
    assert_eq!(meta.get("merge_alpha"), Some("1"));
    assert!(meta.get("merge_radius").is_some());
    let o = render(&["--alpha", "0.5"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}
