//! The probe that sets τ, the threshold of BDPT's Russian roulette on visibility rays
//! (`transport::subpath::shadow_survival`): a fixed, cheap path-traced image of the scene. Both
//! backends take τ from here, so that they roulette the same connections.

use super::render_pass;
use crate::film::Film;
use crate::layout::FlatScene;
use crate::transport::camera::Camera;
use crate::transport::faults::Faults;
use crate::transport::method::Method;
use crate::transport::subpath::SHADOW_RR_FRACTION;

/// The probe: a fixed, cheap path-traced image of what `camera` sees of `scene` (32x32 pixels,
/// 4 samples, seed 0), the same for any image size, seed, pass schedule or resumption.
pub fn probe_film(scene: &FlatScene, camera: &Camera) -> Film {
    let mut probe_camera = *camera;
    probe_camera.width = 32;
    probe_camera.height = 32;
    let mut film = Film::new(32, 32);
    render_pass(scene, &probe_camera, 0, 0, 4, 1, Faults::NONE, &mut film);
    film
}

/// τ for a scene and camera: [`SHADOW_RR_FRACTION`] of the image's mean radiance (its largest
/// channel), estimated by the probe ([`probe_film`]), so that τ is the same on both backends and
/// for any seed, pass schedule or resumption.
pub fn shadow_threshold(scene: &FlatScene, camera: &Camera) -> f32 {
    let (mean, _) = probe_film(scene, camera).image_mean();
    let m = mean[0].max(mean[1]).max(mean[2]) as f32;
    if m.is_finite() {
        SHADOW_RR_FRACTION * m
    } else {
        0.0
    }
}

/// τ for a render of `method`: [`shadow_threshold`] where the method connects subpaths (BDPT,
/// VCM), and 0 (no roulette) for the others.
pub fn shadow_threshold_for(method: Method, scene: &FlatScene, camera: &Camera) -> f32 {
    if method.connects() {
        shadow_threshold(scene, camera)
    } else {
        0.0
    }
}
