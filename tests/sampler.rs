//! The Sobol sampler (`--sampler sobol`, `src/math/sampling.rs`): the shader holds the same
//! direction numbers, both backends render the same images from the same points, the images
//! are unbiased, and the standard error a film claims from its two independent streams is the
//! real one.
//!
//! Statistics: the furnace's |mean − 1| ≤ 4 s.e. per channel (`tests/furnace.rs`); for the
//! standard error, (k − 1) s² / σ̂² against χ²(k − 1) over k seeds (`tests/standard_error.rs`).
//! Within one stream the samples are stratified against each other, so their own scatter
//! overstates the error of their mean: that estimate, planted, is shown to be rejected.

use crate::common::*;
use crate::standard_error::chi_square_of_scatter;
use hexray::film::Film;
use hexray::math::sampling::{SamplerKind, SOBOL_BITS, SOBOL_DIRECTIONS};
use hexray::transport::faults::Faults;
use hexray::transport::method::Method;

/// `sobol4_reversed` in `shaders/sampling.wgsl` xors, for bit k of the index, the row k of
/// `SOBOL_DIRECTIONS`, masked by bit 31 − k of the reversed index: line for line the table.
#[test]
fn the_shaders_sobol_directions_are_the_rust_table() {
    let source = include_str!("../shaders/sampling.wgsl");
    let hex = |s: &str| {
        u32::from_str_radix(s.trim().trim_end_matches('u').trim_start_matches("0x"), 16).unwrap()
    };
    let rows: Vec<([u32; 4], u32)> = source
        .lines()
        .filter_map(|l| {
            l.trim()
                .strip_prefix("x ^= select(vec4<u32>(0u), vec4<u32>(")
        })
        .map(|rest| {
            let (numbers, mask) = rest.split_once("), (index_reversed & ").unwrap();
            let v: Vec<u32> = numbers.split(',').map(hex).collect();
            let mask = hex(mask.split_once(')').unwrap().0);
            ([v[0], v[1], v[2], v[3]], mask)
        })
        .collect();
    assert_eq!(rows.len(), SOBOL_BITS as usize);
    for (k, (row, mask)) in rows.iter().enumerate() {
        assert_eq!(*row, SOBOL_DIRECTIONS[k], "row {k}");
        assert_eq!(*mask, 1u32 << (31 - k), "row {k}'s bit");
    }
}

/// With the Sobol sampler the GPU renders what the CPU does, sample for sample: path tracing
/// on cornell_box and vcm (whose light subpaths draw Sobol points too) on tncg15_room. Both
/// sums, the even samples' too, so the standard errors agree as well.
#[test]
fn sobol_renders_are_the_same_on_both_backends() {
    if gpu().is_none() {
        return;
    }
    for (rel, method, spp) in [
        ("scenes/cornell_box.json", Method::Path, 16),
        ("scenes/tncg15_room.json", Method::Vcm, 6),
    ] {
        let render = Render::file(rel)
            .size(32, 32)
            .spp(spp)
            .seed(5)
            .method(method)
            .sampler(SamplerKind::Sobol);
        let (cpu, gpu) = (render.cpu(), render.gpu());
        let (differing, worst) = pixels_differing(&cpu, &gpu, 1e-6);
        assert!(
            differing <= 2,
            "{rel} {method}: {differing} of 1024 pixels differ (worst relMSE term {worst:e})"
        );
        let (se_cpu, se_gpu) = (cpu.image_mean().1, gpu.image_mean().1);
        for c in 0..3 {
            assert!(
                (se_cpu[c] - se_gpu[c]).abs() <= 1e-3 * se_cpu[c],
                "{rel} {method}: s.e. {se_cpu:?} on the CPU, {se_gpu:?} on the GPU"
            );
        }
    }
}

/// 200 path-traced renders of cornell_box (16x16, 64 spp, seeds 1000 to 1199) with the Sobol
/// sampler, once per test binary.
fn sobol_films() -> &'static [Film] {
    use std::sync::OnceLock;
    static FILMS: OnceLock<Vec<Film>> = OnceLock::new();
    FILMS.get_or_init(|| {
        (1000..1200)
            .map(|seed| {
                Render::file("scenes/cornell_box.json")
                    .size(16, 16)
                    .spp(64)
                    .seed(seed)
                    .sampler(SamplerKind::Sobol)
                    .cpu()
            })
            .collect()
    })
}

/// The image mean's claimed variance (red channel) of each film, estimated as `sampler` would.
fn claims_as(sampler: SamplerKind) -> Vec<(f64, f64)> {
    sobol_films()
        .iter()
        .map(|film| {
            let film = film.clone().with_sampler(sampler);
            let (m, se) = film.image_mean();
            (m[0], se[0] * se[0])
        })
        .collect()
}

/// The standard error from the two streams matches the scatter of image means across seeds.
#[test]
fn sobol_standard_error_matches_the_scatter_across_seeds() {
    let (stat, ok) = chi_square_of_scatter("sobol, two streams", &claims_as(SamplerKind::Sobol));
    assert!(ok, "the streams' standard error is off: χ² = {stat:.2}");
}

/// Planted: the samples' own scatter, as if they were independent, claims more error than
/// there is, and the same statistic rejects it.
#[test]
fn sobol_standard_error_from_the_samples_scatter_is_rejected() {
    let (stat, ok) = chi_square_of_scatter(
        "sobol, samples taken as independent",
        &claims_as(SamplerKind::Independent),
    );
    assert!(!ok, "the within-stream estimate passed: χ² = {stat:.2}");
}

/// The furnace of `rel` with the Sobol sampler on `backend`: 32x32, 128 spp (seed 40).
fn sobol_furnace(backend: Backend, rel: &str, faults: Faults) -> Film {
    Render::file(rel)
        .size(32, 32)
        .spp(128)
        .seed(40)
        .faults(faults)
        .sampler(SamplerKind::Sobol)
        .on(backend)
}

on_each_backend! {
    /// The Sobol sampler's images are unbiased: a glass sphere in a furnace (every lobe,
    /// Russian roulette) converges to 1 within 4 of its claimed standard errors.
    fn sobol_glass_sphere_in_a_furnace_converges_to_1(backend) {
        let film = sobol_furnace(backend, "scenes/furnace/glass_sphere.json", Faults::NONE);
        assert_mean_within_4_se(&film, [1.0; 3], &format!("{backend} sobol glass sphere"));
    }

    /// Planted: a mirror that keeps 97 % of the light is caught by the same check.
    fn sobol_furnace_rejects_a_dim_mirror(backend) {
        let dim = Faults { specular_scale: 0.97, ..Faults::NONE };
        let film = sobol_furnace(backend, "scenes/furnace/mirror_sphere.json", dim);
        let (_, _, z) = image_mean_z(&film, [1.0; 3]);
        assert!(
            z.iter().any(|z| z.abs() > 4.0),
            "{backend}: a 97 % mirror passed the sobol furnace (z {z:?})"
        );
    }
}
