//! Photon merging's radius and its schedule over iterations (`--method sppm|vcm`).
//!
//! A merge estimates the light arriving at a camera vertex x from the light vertices
//! (photons) y of the iteration's N light subpaths with |y − x| < r, each counted with the
//! disk kernel 1 / (π r²) and divided by N (density estimation on the surface). The estimate is
//! biased by the light's variation over the disk, by O(r²) where it is smooth, and consistent
//! as r shrinks: iteration i (from 1) merges within
//!
//!   r_i = r_1 · i^((α − 1) / 2),
//!
//! Knaus and Zwicker's schedule ("Progressive photon mapping: a probabilistic approach", 2011,
//! eq. 16, as SmallVCM uses it), with 0 < α < 1: the variance of iteration i grows as
//! 1 / r_i² ∝ i^(1 − α) while its bias falls as r_i² ∝ i^(α − 1); the average over n iterations
//! converges with both going to 0. The schedule depends only on the iteration index, so passes,
//! threads, backends and resumption all merge within the same radii.

use crate::layout::FlatScene;

/// The default initial radius of `sppm` and `vcm-full` as a share of the scene's bounding-sphere
/// radius (half the diagonal of its bounding box): 0.01, at every image size. Scene-relative, as
/// SmallVCM's `-r` is: merging's bias is set by the disk's size in the scene, not in pixels. The
/// caustics of the rooms with mirrors and glass want a wider disk, the Cornell box (no specular
/// surface, so merging only adds its bias there) a narrower one. At 0.01 instead of SmallVCM's
/// 0.003, sppm's relMSE (the references' noise subtracted) is 0.15, 0.16 and 0.13 of 0.003's on
/// tncg15_room, glass_room and cornell_box, and that of Georgiev's VCM (`vcm-full`) 0.77, 0.84
/// and 1.10 (CPU, 256x256, 30 s; `METHOD=sppm benches/merge_radius.sh`, `METHOD=vcm-full`). The
/// wider disk pays less as the iterations grow: the squared bias falls as n^(2α − 2), the
/// variance as n^−α, so renders of thousands of iterations are better served by
/// [`HARDWARE_GPU_RADIUS_FACTOR`] or a smaller `--alpha`. The measurements, and why the radius
/// does not scale with the image size: docs/journal/2026-11-27_merge_radius.md.
pub const DEFAULT_RADIUS_FACTOR: f32 = 0.01;

/// The merge radius's default on a hardware GPU, as a share of the scene's bounding-sphere
/// radius: 0.003. Such a GPU runs tens to hundreds of times the iterations of the CPU backend in
/// the same time, so its renders are long in iterations, and in long renders the squared bias of
/// a wide disk outlasts the variance it saves (see [`DEFAULT_RADIUS_FACTOR`]). On an NVIDIA H200
/// at 512x512 in 4 s (1200 – 2300 iterations), vcm's relMSE (the references' noise subtracted)
/// at 0.003 is 0.28, 0.24 and 0.21 of that at 0.01 on tncg15_room, glass_room and cornell_box
/// (docs/records/2026-11-27_h200/first_diffuse_radius_512.txt). A software adapter (lavapipe)
/// runs about as many iterations as the CPU backend and keeps [`DEFAULT_RADIUS_FACTOR`].
pub const HARDWARE_GPU_RADIUS_FACTOR: f32 = 0.003;

/// The default initial radius of `vcm`, which merges within each vertex's clearance
/// ([`local_radius`]), as a share of the scene's bounding-sphere radius: 0.03 (the other merging
/// methods keep [`DEFAULT_RADIUS_FACTOR`]). Where surfaces meet, a disk that reaches across the
/// edge counts the photons of the wrong surface and misses the light behind it: at 0.02 of the
/// scene radius on tncg15_room, 89 % of the squared bias (in 4x4-pixel blocks) lay in 5 % of
/// the image, the room's edges and outlines. Within the clearance that bias is gone, and the
/// flat walls bear a disk three times as wide: on tncg15_room vcm's relMSE at 0.03 within the
/// clearance (floor 0.1) is 2.2e-4, against 6.1e-4 at 0.01 everywhere (CPU, 256x256, 30 s,
/// seeds 11 and 12). The radii and floors measured: docs/journal/2026-11-27_clearance.md.
pub const VCM_RADIUS_FACTOR: f32 = 0.03;

/// The least share of the iteration's radius that [`local_radius`] gives a vertex near another
/// surface: 0.1 (measured with [`VCM_RADIUS_FACTOR`]). Without one, merges at an edge would
/// shrink to nothing; the MIS weights then give those paths to the connections, which is right
/// for most, but the paths that only merging samples (a caustic seen in a mirror) would grow
/// noisy there.
pub const CLEARANCE_FLOOR: f32 = 0.1;

/// The default α: SmallVCM's and Knaus and Zwicker's 0.75.
pub const DEFAULT_ALPHA: f32 = 0.75;

/// The merge radius of a render: r_1 in scene units and α.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergeRadius {
    pub initial: f32,
    pub alpha: f32,
}

impl MergeRadius {
    /// The radius of iteration `iteration` (counted from 0, so the first is r_1).
    #[inline]
    pub fn at(&self, iteration: u32) -> f32 {
        let i = iteration as f64 + 1.0;
        (self.initial as f64 * i.powf((self.alpha as f64 - 1.0) * 0.5)) as f32
    }

    /// The default of `method` for a scene: [`VCM_RADIUS_FACTOR`] (vcm) or
    /// [`DEFAULT_RADIUS_FACTOR`] (sppm, vcm-full) of its bounding-sphere radius, α =
    /// [`DEFAULT_ALPHA`].
    pub fn default_for(scene: &FlatScene, method: crate::transport::method::Method) -> MergeRadius {
        let factor = if method.merges_within_clearance() {
            VCM_RADIUS_FACTOR
        } else {
            DEFAULT_RADIUS_FACTOR
        };
        MergeRadius::of_scene(scene, factor)
    }

    /// r_1 at `factor` of `scene`'s bounding-sphere radius, α = [`DEFAULT_ALPHA`].
    pub fn of_scene(scene: &FlatScene, factor: f32) -> MergeRadius {
        MergeRadius {
            initial: factor * scene_radius(scene),
            alpha: DEFAULT_ALPHA,
        }
    }

    /// This radius with r_1 at the hardware GPU's default share of `scene`'s bounding-sphere
    /// radius ([`HARDWARE_GPU_RADIUS_FACTOR`]), α kept.
    pub fn for_hardware_gpu(self, scene: &FlatScene) -> MergeRadius {
        MergeRadius {
            alpha: self.alpha,
            ..MergeRadius::of_scene(scene, HARDWARE_GPU_RADIUS_FACTOR)
        }
    }
}

/// The merge radius at a camera vertex `p` on primitive `prim` of an iteration that merges within
/// `radius` (`vcm`, [`crate::transport::method::Method::merges_within_clearance`]): the vertex's
/// clearance (`crate::transport::clearance`), at most `radius` and at least [`CLEARANCE_FLOOR`] of
/// it. Within its clearance the disk lies on the vertex's own plane in front of every other
/// surface, so the merge is free of the bias where surfaces meet (the room's edges, an emitter's
/// outline, what stands on the floor), which held most of merging's bias (see
/// [`VCM_RADIUS_FACTOR`]). The schedule still shrinks it over iterations: consistent as before.
pub fn local_radius(scene: &FlatScene, p: glam::Vec3, prim: u32, radius: f32) -> f32 {
    crate::transport::clearance::clearance(scene, p, prim, radius).max(CLEARANCE_FLOOR * radius)
}

/// The merge radius at camera vertex `p` on primitive `prim` as a share of the iteration's
/// `radius`: [`local_radius`] / `radius` where the method merges `within_clearance`, else 1.
/// Every strategy of a path through the vertex weighs the merge there with this radius
/// (`MergeMis::within`; `crate::transport::subpath`, "A radius of the vertex").
pub fn merge_share(
    scene: &FlatScene,
    p: glam::Vec3,
    prim: u32,
    radius: f32,
    within_clearance: bool,
) -> f32 {
    if !within_clearance {
        return 1.0;
    }
    // Where the clearance reaches the radius the share is 1 exactly, on both backends: WGSL's
    // division need not give r / r = 1 (shaders/merging.wgsl, the same step).
    let local = local_radius(scene, p, prim, radius);
    if local >= radius {
        1.0
    } else {
        local / radius
    }
}

/// The merge kernel's normalisation for one iteration: the disk's 1 / (π r² N), shared by the
/// N light subpaths; 0 at radius 0 (no merging). `ball_kernel` is the test-only fault
/// `Faults::merge_kernel_ball`, the 3-D ball's 1 / (4/3 π r³ N).
pub fn kernel_normalization(radius: f32, n_light_paths: u32, ball_kernel: bool) -> f32 {
    let n = n_light_paths as f32;
    if radius <= 0.0 {
        0.0
    } else if ball_kernel {
        1.0 / (4.0 / 3.0 * std::f32::consts::PI * radius.powi(3) * n)
    } else {
        1.0 / (std::f32::consts::PI * radius * radius * n)
    }
}

/// Half the diagonal of the bounding box of the scene's triangles and spheres.
pub fn scene_radius(scene: &FlatScene) -> f32 {
    let (lo, hi) = scene_bounds(scene);
    0.5 * (hi - lo).length()
}

/// The bounding box of the scene's triangles and spheres (zero for an empty scene): the hash
/// grid's origin on both backends.
pub fn scene_bounds(scene: &FlatScene) -> (glam::Vec3, glam::Vec3) {
    use glam::Vec3;
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for t in &scene.triangles {
        for v in [t.v0, t.v1, t.v2] {
            lo = lo.min(v.into());
            hi = hi.max(v.into());
        }
    }
    for s in &scene.spheres {
        let c = Vec3::from(s.center);
        lo = lo.min(c - s.radius);
        hi = hi.max(c + s.radius);
    }
    if lo.x > hi.x {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_radius_shrinks_as_the_schedule_says() {
        let r = MergeRadius {
            initial: 2.0,
            alpha: 0.75,
        };
        assert_eq!(r.at(0), 2.0);
        // r_4 = r_1 · 4^(−1/8).
        assert!((r.at(3) - 2.0 * 4f32.powf(-0.125)).abs() < 1e-6);
        assert!(r.at(100) < r.at(99));
    }
}
