//! Light tracing (`--method light`) is unbiased wherever the camera sees no mirror or glass: on
//! cornell_box, which has none, it renders path tracing's image.
//!
//! Statistic: `tests/gpu_parity.rs`'s, between a light-traced and a path-traced render of other
//! seeds: per 8x8 block and channel, Welch's t-test with a Bonferroni correction at α = 0.01
//! overall, and each channel's image-mean ratio within 4 s.e. of 1 (light tracing's s.e. from
//! its batch means). Power: a camera importance that lacks one cos θ, 1 / (A cos²θ) instead of
//! 1 / (A cos³θ), dims the image by cos θ toward its edges (3 % in the image mean of
//! cornell_box's view) and is rejected (69 of 192 block-channels, mean ratio z −10 to −14).
//!
//! Splats are order-independent: the same light-traced film, rendered with one thread and with
//! two (the threads' splats interleave differently), and twice on the GPU (whose invocations
//! run in no fixed order), is bit-identical.

use crate::common::parity::parity;
use crate::common::*;
use hexray::film::Film;
use hexray::transport::faults::Faults;
use hexray::transport::method::Method;

const SCENE: &str = "scenes/cornell_box.json";
const SIZE: u32 = 64;

fn light_against_path(faults: Faults) -> crate::common::parity::Parity {
    let render = Render::file(SCENE).size(SIZE, SIZE).spp(256);
    let path = render.seed(70).cpu();
    let light = render.seed(71).method(Method::Light).faults(faults).cpu();
    let p = parity(&path, &light);
    eprintln!("light tracing against path tracing on cornell_box: {p}");
    p
}

#[test]
fn light_tracing_renders_path_tracings_image_where_nothing_specular_is_seen() {
    let p = light_against_path(Faults::NONE);
    assert!(p.same(), "{p}");
}

#[test]
fn light_tracing_test_rejects_an_importance_missing_a_cosine() {
    let faults = Faults {
        importance_missing_cos: true,
        ..Faults::NONE
    };
    let p = light_against_path(faults);
    assert!(
        !p.same(),
        "an importance without one cos θ went unnoticed: {p}"
    );
}

fn same_bits(a: &Film, b: &Film) -> bool {
    a.pixels == b.pixels && a.iteration_means == b.iteration_means
}

#[test]
fn light_tracing_is_bit_identical_for_any_thread_count() {
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                Render::file(SCENE)
                    .size(32, 32)
                    .spp(4)
                    .seed(72)
                    .method(Method::Light)
                    .cpu()
            })
    };
    let (one, two) = (on(1), on(2));
    assert!(
        same_bits(&one, &two),
        "the splat sums depend on the threads"
    );
    assert!(one.pixels.iter().any(|p| p.sum[0] > 0.0));
}

#[test]
fn gpu_light_tracing_is_bit_identical_from_run_to_run() {
    if gpu().is_none() {
        return;
    }
    let render = Render::file(SCENE)
        .size(32, 32)
        .spp(4)
        .seed(73)
        .method(Method::Light);
    let (a, b) = (render.gpu(), render.gpu());
    assert!(
        same_bits(&a, &b),
        "the GPU's splat sums depend on the order of its invocations"
    );
    assert!(a.pixels.iter().any(|p| p.sum[0] > 0.0));
}
