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
use hexray::transport::faults::Faults;

const SCENE: &str = "scenes/stability/caustic.json";
const REFERENCE: &str = "tests/data/references/stability/caustic_32.exr";

#[test]
fn caustic_is_unbiased_on_the_cpu() {
    let film = render_cpu(SCENE, 32, 32, 4096, 31, Faults::NONE);
    assert_eq!(film.dropped(), 0, "non-finite samples");
    let z = film_mean_z("caustic, CPU", &film, REFERENCE);
    assert!(means_agree(z), "z {z:?}");
}

/// The GPU renders 16x16 pixels (lavapipe is slow): the same image mean, from 1 million samples.
#[test]
fn caustic_is_unbiased_on_the_gpu() {
    let Some(gpu) = gpu() else { return };
    let film = render_gpu(gpu, SCENE, 16, 16, 4096, 32, Faults::NONE);
    assert_eq!(film.dropped(), 0, "non-finite samples");
    let z = film_mean_z("caustic, GPU", &film, REFERENCE);
    assert!(means_agree(z), "z {z:?}");
}

#[test]
fn caustic_test_rejects_glass_that_passes_10_percent_less() {
    let dim = Faults {
        specular_scale: 0.9,
        ..Faults::NONE
    };
    let film = render_cpu(SCENE, 32, 32, 4096, 31, dim);
    let z = film_mean_z("caustic, CPU, dim glass", &film, REFERENCE);
    assert!(!means_agree(z), "dim glass passed: z {z:?}");
}
