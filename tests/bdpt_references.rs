//! BDPT is unbiased against references it had no part in: Mitsuba 3's cornell_box (the test
//! path tracing passes in `tests/independent_renderer.rs`, same statistic), and path tracing's
//! long references of tncg15_room, glass_room, the caustic and the 10^2 tiny light (32x32,
//! 65536 spp, `docs/figures/stability.sh references`).
//!
//! Statistics: against Mitsuba, 4x4 blocks with fewer than 0.1 % of block-channels beyond 5 s.e.
//! and the image-mean ratio within 4 s.e.; against the long references, the image mean within 4
//! combined s.e. (BDPT's from its batch means) and, where the variance is not heavy-tailed
//! (tncg15_room, glass_room), Welch's t per 8x8 block with Bonferroni at α = 0.01. The caustic
//! and the tiny light are compared by their image means only, as their path-traced tests are:
//! a block's few thousand samples may hold none of the rare bright paths, and then its sample
//! variance is wrong too. Planted: tncg15_room's mirrors 10 % dim, the light that reaches its
//! walls from the mirror wall counted twice (next-event estimation through the mirror, and the
//! other strategies without their partition, `planar_mirror`), and the caustic's glass 10 %
//! dim, each rejected.

use crate::common::reference::{compare, film_mean_z, means_agree, read};
use crate::common::*;
use crate::independent_renderer::compare_with_mitsuba;
use hexray::analysis::stats::MeanImage;
use hexray::transport::faults::Faults;
use hexray::transport::method::Method;

const TNCG15_REFERENCE: &str = "tests/data/references/stability/tiny_light_1e0_32.exr";
const GLASS_REFERENCE: &str = "tests/data/references/stability/glass_room_32.exr";
const CAUSTIC_REFERENCE: &str = "tests/data/references/stability/caustic_32.exr";
const TINY_LIGHT_REFERENCE: &str = "tests/data/references/stability/tiny_light_1e2_32.exr";

const DIM_SPECULAR: Faults = Faults {
    specular_scale: 0.9,
    ..Faults::NONE
};

fn assert_agrees_with_mitsuba(film: &hexray::film::Film) {
    let (beyond, ratio_z) = compare_with_mitsuba(&MeanImage::from_film(film));
    assert!(
        beyond < 0.001,
        "{:.3} % of block-channels beyond 5 s.e.",
        100.0 * beyond
    );
    assert!(
        ratio_z.iter().all(|z| z.abs() <= 4.0),
        "image-mean ratio z {ratio_z:?}"
    );
}

on_each_backend! {
    /// 64 iterations: on the CPU at 256x256 (seed 13), on the GPU at 128x128 (seed 14).
    fn bdpt_cornell_box_agrees_with_mitsuba(backend) {
        let (size, seed) = match backend {
            Backend::Cpu => (256, 13),
            Backend::Gpu => (128, 14),
        };
        let film = Render::file("scenes/cornell_box.json")
            .size(size, size)
            .spp(64)
            .seed(seed)
            .method(Method::Bdpt)
            .on(backend);
        assert_agrees_with_mitsuba(&film);
    }
}

/// BDPT at 32x32, `iterations` iterations, against a path-traced reference, blocks and mean.
fn against_reference(
    rel: &str,
    reference: &str,
    iterations: u32,
    seed: u32,
    faults: Faults,
) -> bool {
    let film = Render::file(rel)
        .size(32, 32)
        .spp(iterations)
        .seed(seed)
        .method(Method::Bdpt)
        .faults(faults)
        .cpu();
    assert_eq!(film.dropped(), 0, "non-finite samples");
    compare(
        &format!("BDPT {rel}"),
        &MeanImage::from_film(&film),
        &read(reference),
    )
    .agrees()
}

#[test]
fn bdpt_agrees_with_path_tracings_reference_of_tncg15_room() {
    assert!(against_reference(
        "scenes/tncg15_room.json",
        TNCG15_REFERENCE,
        1024,
        15,
        Faults::NONE
    ));
}

#[test]
fn bdpt_agrees_with_path_tracings_reference_of_glass_room() {
    assert!(against_reference(
        "scenes/glass_room.json",
        GLASS_REFERENCE,
        1024,
        16,
        Faults::NONE
    ));
}

#[test]
fn bdpt_reference_test_rejects_mirrors_10_percent_dim() {
    assert!(!against_reference(
        "scenes/tncg15_room.json",
        TNCG15_REFERENCE,
        1024,
        15,
        DIM_SPECULAR
    ));
}

#[test]
fn bdpt_reference_test_rejects_light_by_a_planar_mirror_counted_twice() {
    // Next-event estimation through the mirror wall takes the light that reaches a diffuse
    // vertex from the mirror with weight 1; with the other strategies' weights left on those
    // paths as well, that light is counted about twice.
    assert!(!against_reference(
        "scenes/tncg15_room.json",
        TNCG15_REFERENCE,
        1024,
        15,
        Faults {
            mirror_light_twice: true,
            ..Faults::NONE
        }
    ));
}

fn mean_against_reference(rel: &str, reference: &str, seed: u32, faults: Faults) -> bool {
    let film = Render::file(rel)
        .size(32, 32)
        .spp(2048)
        .seed(seed)
        .method(Method::Bdpt)
        .faults(faults)
        .cpu();
    assert_eq!(film.dropped(), 0, "non-finite samples");
    means_agree(film_mean_z(&format!("BDPT {rel}"), &film, reference))
}

#[test]
fn bdpt_caustic_is_unbiased() {
    assert!(mean_against_reference(
        "scenes/stability/caustic.json",
        CAUSTIC_REFERENCE,
        17,
        Faults::NONE
    ));
}

#[test]
fn bdpt_caustic_test_rejects_glass_10_percent_dim() {
    assert!(!mean_against_reference(
        "scenes/stability/caustic.json",
        CAUSTIC_REFERENCE,
        17,
        DIM_SPECULAR
    ));
}

#[test]
fn bdpt_tiny_light_1e2_is_unbiased() {
    assert!(mean_against_reference(
        "scenes/stability/tiny_light_1e2.json",
        TINY_LIGHT_REFERENCE,
        18,
        Faults::NONE
    ));
}
