//! The safety net under every method: an image that is black, or nearly, where light from the
//! scene's emitters reaches the camera. A method can miss light that is there and still exit
//! cleanly (light tracing sees nothing through mirrors and glass; a method that picks emitters
//! by power can nearly always pick one whose light never reaches the view; a merge radius far
//! too wide for the view darkens the whole image), and nothing else would say so. The judge is
//! the cheap path-traced probe that also sets BDPT's τ (`shadow_probe::probe_film`): unbiased,
//! a few thousand paths, the same for every method.

use super::shadow_probe::probe_film;
use crate::layout::FlatScene;
use crate::transport::camera::Camera;
use crate::transport::method::Method;

/// An image is nearly black when its mean radiance (largest channel) is below this share of the
/// probe's: 0.1. Methods that converge to the same image differ far less than that; one that
/// leaves out a kind of light (light tracing's mirrors) can fall below half, and is still
/// rendering what it says it renders.
pub const DARK_SHARE: f64 = 0.1;

/// The probe must see light clearly to judge: its mean (largest channel) at least this many of
/// its standard errors above 0.
pub const PROBE_Z: f64 = 5.0;

/// A warning for an image of `method` whose mean radiance per channel is `mean`, where it is
/// nearly black ([`DARK_SHARE`]) while the probe sees the emitters' light reach the camera
/// ([`PROBE_Z`]); None otherwise, and for path tracing, which the probe is.
pub fn dark_image_warning(
    scene: &FlatScene,
    camera: &Camera,
    method: Method,
    mean: [f64; 3],
) -> Option<String> {
    if method == Method::Path {
        return None;
    }
    let (probe, se) = probe_film(scene, camera).image_mean();
    let largest = |v: [f64; 3]| v[0].max(v[1]).max(v[2]);
    let (seen, seen_se) = (largest(probe), largest(se));
    let got = largest(mean);
    // A NaN mean warns too.
    let dark = got.is_nan() || got < DARK_SHARE * seen;
    (seen > PROBE_Z * seen_se && dark).then(|| {
        format!(
            "the image is nearly black (mean radiance {got:.3e}) where a path-traced probe sees \
             light reach the camera (mean {seen:.3e} ± {seen_se:.1e}): --method {method} misses \
             most of this scene's light. --method path or bdpt render it"
        )
    })
}
