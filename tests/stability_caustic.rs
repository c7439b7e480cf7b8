//! Caustic: a glass sphere focuses a small light onto a diffuse floor
//! (`scenes/stability/caustic.json`). Under the sphere, shadow rays toward the light hit the
//! glass, so next-event estimation contributes nothing there: the focused light is found only by
//! BSDF-sampled paths floor -> glass -> glass -> light, whose emission counts in full after the
//! specular bounces. Such paths are rare and bright (heavy-tailed samples): the property is that
//! the estimate is nevertheless unbiased and finite on both backends.
//!
//! Statistic: each channel's image mean against a long CPU reference of the same scene (32x32,
//! 65536 spp, another seed; `docs/figures/stability.sh references`), within 4 combined standard errors
//! (false alarm 6e-5 per channel), and no sample dropped as non-finite. Only the image mean: a
//! small block's few thousand samples may hold none of the rare caustic paths, and then its
//! sample variance, not just its mean, is wrong, so per-block t-tests would reject a correct
//! renderer; the image pools 4 million samples and thousands of caustic paths. Power: glass that
//! passes 10 % less light (`specular_scale` 0.9, the caustic 19 % darker) is rejected.

use crate::common::reference::{film_mean_z, means_agree};
use crate::common::*;
use hexray::film::Film;
use hexray::transport::faults::Faults;

const SCENE: &str = "scenes/stability/caustic.json";
const REFERENCE: &str = "tests/data/references/stability/caustic_32.exr";

/// 4096 samples per pixel: on the CPU 32x32 (seed 31); on the GPU 16x16 (lavapipe is slow;
/// seed 32), the same image mean from 1 million samples.
fn caustic(backend: Backend, faults: Faults) -> Film {
    let (size, seed) = match backend {
        Backend::Cpu => (32, 31),
        Backend::Gpu => (16, 32),
    };
    Render::file(SCENE)
        .size(size, size)
        .spp(4096)
        .seed(seed)
        .faults(faults)
        .on(backend)
}

on_each_backend! {
    fn caustic_is_unbiased(backend) {
        let film = caustic(backend, Faults::NONE);
        assert_eq!(film.dropped(), 0, "{backend}: non-finite samples");
        let z = film_mean_z(&format!("caustic, {backend}"), &film, REFERENCE);
        assert!(means_agree(z), "{backend}: z {z:?}");
    }
}

#[test]
fn caustic_test_rejects_glass_that_passes_10_percent_less() {
    let dim = Faults {
        specular_scale: 0.9,
        ..Faults::NONE
    };
    let film = caustic(Backend::Cpu, dim);
    let z = film_mean_z("caustic, CPU, dim glass", &film, REFERENCE);
    assert!(!means_agree(z), "dim glass passed: z {z:?}");
}
