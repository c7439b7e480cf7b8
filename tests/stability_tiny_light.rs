//! Tiny light: `tncg15_room` with its light shrunk to 1/100 of the area and its radiance raised
//! 100-fold (`scenes/stability/tiny_light_1e2.json`). Next-event estimation keeps the direct
//! light as clean as before, but paths diffuse -> mirror -> light, which only BSDF sampling
//! finds, become 100 times rarer and brighter: the property is that the estimate stays unbiased.
//!
//! Statistic: each channel's image mean against a long CPU reference of the same scene (32x32,
//! 65536 spp, another seed; `docs/figures/stability.sh references`), within 4 combined standard errors
//! (false alarm 6e-5 per channel). Only the image mean, as for the caustic: the mirror paths to
//! the light are too rare for a small block's sample variance to be right at a test's sample
//! count, while the image's 4 million samples hold hundreds of them. The light shrunk
//! 10^4-fold is tested for finite, non-negative pixels only: at any sample count that fits a
//! default test its expected number of mirror paths to the light is below one, so no
//! finite-sample statistic can both hold its false-alarm rate and have power there. Its
//! unbiasedness takes a render as long as its reference (the ignored test at the end, 268
//! million paths); docs/stability.md measures its error against time.
//! Power: the usual biased answer to fireflies, clamping each sample's radiance (here at 100, 5 %
//! of the light's radiance, which also clips the light where the camera sees it), is rejected.
//! (Mirrors 3 % too dark, the course report's bug, move this image's mean less than its
//! heavy-tailed standard error; `stability_mirror.rs` catches those.)

use crate::common::reference::{film_mean_z, means_agree};
use crate::common::*;
use hexray::cpu::trace_path;
use hexray::film::Film;
use hexray::math::sampling::Sampler;
use hexray::transport::camera::Camera;
use hexray::transport::faults::Faults;
use rayon::prelude::*;

const SCENE: &str = "scenes/stability/tiny_light_1e2.json";
const REFERENCE: &str = "tests/data/references/stability/tiny_light_1e2_32.exr";

on_each_backend! {
    /// 4096 samples per pixel: on the CPU 32x32 (seed 41); on the GPU 16x16 (lavapipe is slow;
    /// seed 42), the same image mean from 1 million samples.
    fn light_100_times_smaller_is_unbiased(backend) {
        let (size, seed) = match backend {
            Backend::Cpu => (32, 41),
            Backend::Gpu => (16, 42),
        };
        let film = Render::file(SCENE)
            .size(size, size)
            .spp(4096)
            .seed(seed)
            .on(backend);
        assert_eq!(film.dropped(), 0, "{backend}: non-finite samples");
        let z = film_mean_z(&format!("tiny light 1e2, {backend}"), &film, REFERENCE);
        assert!(means_agree(z), "{backend}: z {z:?}");
    }
}

/// A renderer that clamps every sample to at most `clamp` per channel: the CPU integrator's
/// samples, clamped before they reach the film.
fn render_clamped(width: u32, height: u32, spp: u32, seed: u32, clamp: f32) -> Film {
    let (scene, flat) = load(SCENE);
    let camera = Camera::new(&scene.desc.camera, width, height);
    let mut film = Film::new(width, height);
    film.pixels.par_iter_mut().enumerate().for_each(|(i, px)| {
        let (x, y) = (i as u32 % width, i as u32 / width);
        let mut rays = 0;
        for s in 0..spp {
            let sampler = Sampler::new(seed, i as u32, s);
            let l = trace_path(&flat, &camera, x, y, &sampler, 1, Faults::NONE, &mut rays);
            px.add(l.min(glam::Vec3::splat(clamp)));
        }
    });
    film
}

#[test]
fn tiny_light_test_rejects_a_renderer_that_clamps_fireflies() {
    let film = render_clamped(32, 32, 4096, 41, 100.0);
    let z = film_mean_z(
        "tiny light 1e2, CPU, samples clamped at 100",
        &film,
        REFERENCE,
    );
    assert!(!means_agree(z), "clamped fireflies passed: z {z:?}");
}

const SCENE_1E4: &str = "scenes/stability/tiny_light_1e4.json";
const REFERENCE_1E4: &str = "tests/data/references/stability/tiny_light_1e4_32.exr";

on_each_backend! {
    /// The light shrunk 10^4-fold, as far as a test's budget can see it: each backend renders
    /// it without a non-finite sample and without a negative pixel (its unbiasedness is the
    /// ignored test below and docs/stability.md's expected error). 16x16, 256 spp, seed 43 on
    /// the CPU, 44 on the GPU.
    fn light_10000_times_smaller_renders_finite(backend) {
        let seed = match backend {
            Backend::Cpu => 43,
            Backend::Gpu => 44,
        };
        let film = Render::file(SCENE_1E4)
            .size(16, 16)
            .spp(256)
            .seed(seed)
            .on(backend);
        assert_eq!(film.dropped(), 0, "{backend}: non-finite samples");
        assert!(film
            .pixels
            .iter()
            .all(|p| p.mean().iter().all(|&m| m >= 0.0)));
    }
}

/// The light shrunk 10^4-fold is unbiased: a render as long as the reference (32x32, 262144
/// spp, 268 million paths; a few minutes on 2 cores), whose few hundred rare paths to the light
/// make the image mean's standard error meaningful, agrees with it within 4 s.e.
#[test]
#[ignore = "268 million paths: minutes on 2 cores"]
fn light_10000_times_smaller_is_unbiased_on_the_cpu() {
    let film = Render::file(SCENE_1E4)
        .size(32, 32)
        .spp(262_144)
        .seed(45)
        .cpu();
    assert_eq!(film.dropped(), 0, "non-finite samples");
    let z = film_mean_z("tiny light 1e4, CPU", &film, REFERENCE_1E4);
    assert!(means_agree(z), "z {z:?}");
}
