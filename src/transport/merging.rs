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

/// The default initial radius as a share of the scene's bounding-sphere radius (half the
/// diagonal of its bounding box): scene-relative, as SmallVCM's `-r` is, and SmallVCM's value.
/// Measured (`--radius`, relMSE at 20 s on 2 cores, 256x256, seed 3, one run each, against the
/// references of `docs/methods.sh references` and Mitsuba's cornell_box; BDPT alongside):
///
/// | r_1 / scene radius | 0.001 | 0.003 | 0.01 | 0.03 | bdpt |
/// | --- | --- | --- | --- | --- | --- |
/// | tncg15_room vcm | 3.7e-3 | 3.2e-3 | 2.7e-3 | 5.5e-3 | 3.9e-3 |
/// | glass_room vcm | 2.8e-3 | 2.6e-3 | 2.4e-3 | 5.8e-3 | |
/// | cornell_box vcm | 3.3e-4 | 3.4e-4 | 4.1e-4 | | 2.7e-4 |
/// | tncg15_room sppm | | 6.9e-3 | 1.3e-3 | | |
///
/// 0.01 helps the rooms with mirrors and glass by 6 to 16 % and costs the Cornell box 20 %.
///
/// The wider measurement (2026-11-25, the build with eight-wide nodes and the light subpaths'
/// roulette from bounce 1): the same 20 s renders, seeds 11, 12 and 13, relMSE minus the
/// references' noise, mean of the three and its ratio to 0.003's:
///
/// | r_1 / scene radius | 0.003 | 0.005 | 0.007 | 0.01 | 0.014 |
/// | --- | --- | --- | --- | --- | --- |
/// | tncg15_room vcm | 1.93e-3 | 1.85e-3 (0.96) | 1.82e-3 (0.94) | 1.62e-3 (0.84) | 1.70e-3 (0.88) |
/// | glass_room vcm | 1.95e-3 | 1.87e-3 (0.96) | 1.79e-3 (0.92) | 1.70e-3 (0.87) | 1.74e-3 (0.89) |
/// | cornell_box vcm | 2.28e-4 | 2.40e-4 (1.05) | 2.58e-4 (1.13) | 2.82e-4 (1.24) | 3.13e-4 (1.38) |
///
/// The rooms' caustics want a wider disk, the Cornell box (no specular surface, so merging
/// only adds its bias there) a narrower one; over the three, the geometric mean of the ratios was
/// 0.97 at 0.01 and 0.99 at 0.007, within what three seeds resolved, and the default stayed
/// SmallVCM's 0.003.
///
/// Measured again on 2026-11-27 (build f875e5f: vcm with two camera subpaths behind mirrors and
/// glass, its visibility rays in packets; 30 s renders on 2 cores, 256x256, seeds 11 and 12,
/// relMSE minus the references' noise, mean of the two and its ratio to 0.003's; the GPU path
/// references of `tests/data/references/h100/` and Mitsuba's cornell_box):
///
/// | r_1 / scene radius | 0.003 | 0.006 | 0.01 | 0.013 |
/// | --- | --- | --- | --- | --- |
/// | tncg15_room vcm | 1.42e-3 | 1.28e-3 (0.90) | 1.06e-3 (0.75) | 1.00e-3 (0.70) |
/// | glass_room vcm | 1.49e-3 | 1.40e-3 (0.94) | 1.29e-3 (0.87) | 1.31e-3 (0.88) |
/// | cornell_box vcm | 1.95e-4 | 2.19e-4 (1.12) | 2.34e-4 (1.20) | 2.63e-4 (1.35) |
/// | geometric mean of the ratios | 1 | 0.98 | 0.92 | 0.94 |
///
/// On the CPU at 256x256, 0.01 wins (the bias, from the two seeds' images, grows from about 0
/// to 8e-5 of tncg15_room's 1.13e-3). On an NVIDIA H200 the same day (one render each, seed 5,
/// ratio of 0.01's relMSE to 0.003's, the references' noise subtracted;
/// docs/bench/2026-11-27_h200/radius_equal_time.txt) it does not:
///
/// | GPU | tncg15_room | glass_room | cornell_box |
/// | --- | --- | --- | --- |
/// | vcm, 256x256, 6 s | 0.80 | 1.00 | 1.12 |
/// | vcm, 512x512, 4 s | 1.20 | 1.58 | 2.82 |
/// | sppm, 256x256, 6 s | 0.38 | 0.45 | 0.24 |
/// | sppm, 512x512, 4 s | 2.10 | 2.31 | 1.20 |
///
/// The reading then (refuted below): the best radius falls with the image size, since at
/// 512x512 an iteration has four times the light subpaths, so a disk of the same size holds
/// four times the photons and merging outweighs the other strategies sooner, and each query
/// costs more. A radius in scene units that suits
/// 256x256 is too wide at `render`'s default 512x512. Scaling r_1 as 1 / sqrt(N) (the same
/// photons per disk at every size, a pixel footprint) would follow that: 0.01 at 256x256 is
/// 0.005 at 512x512, which on an NVIDIA H100 the same day (512x512, 4 s, seed 5, one render
/// each; docs/bench/2026-11-27_h200/radius_512_h100.txt) gave 0.85, 1.02 and 1.15 of 0.003's
/// relMSE for vcm (geometric mean 1.00) and 0.92, 0.98 and 0.66 for sppm (0.84). Not made the
/// default then: the tests render at 64x64 and below, where that rule widens the disk further.
///
/// Also, the wider disk lets neighbouring pixels share photons, which the block statistic of
/// the GPU = CPU tests treated as independent (24 seeds of sppm at 64x64 on tncg15_room: block
/// means scatter 1.10x their claimed variance at 0.01, 0.94x at 0.003), and the sppm test
/// rejected one block at p = 1.5e-5 there. Those tests now take their standard errors from the
/// iterations' block means (`tests/common/parity.rs`, `parity_of_iterations`), which accept the
/// same renders at 0.01.
///
/// **The default since 2026-11-27 is 0.01, at every image size** (build 371366e, 2 cores of an
/// Intel Xeon VM; relMSE minus the references' noise as a ratio to 0.003's at α = 0.75, summed
/// over the seeds; docs/bench/merge_radius_2026-11-27_default.md):
///
/// | CPU, vcm | tncg15_room | glass_room | cornell_box |
/// | --- | --- | --- | --- |
/// | 256x256, 30 s, seeds 11 and 12: 0.01 | **0.77** | **0.84** | **1.10** |
/// | the same, 0.01 with α = 2/3 | 0.97 | 0.83 | 1.08 |
/// | the same, 0.015 with α = 2/3 | 0.81 | 0.81 | 1.17 |
/// | 256x256, 120 s (650 – 1340 iterations), seed 13: 0.01 | 0.84 | | 1.06 |
/// | 512x512, 10 s (the README's render), seeds 5 and 6, as 2x2 block means: 0.005 | 0.85 | 0.89 | 1.31 |
/// | the same: 0.0075 | 0.71 | 0.82 | 1.25 |
/// | sppm, 256x256, 30 s, seed 11: 0.01 | 0.15 | 0.16 | 0.13 |
/// | the same: 0.02 | 0.19 | 0.22 | 0.12 |
///
/// The scaling as 1 / sqrt(pixels) was tried and refuted: at 32x32 it makes the disk 0.08 of
/// the scene radius, and the convergence tests' relMSE rose 30 – 300 fold (vcm on the caustic
/// 0.55 at 256 iterations, against 1.9e-3 at 0.01 and 3.6e-3 at 0.003): the bias is set by the
/// disk's size in the scene, not in pixels. A fixed share suits the CPU at both sizes, where
/// the variance of a merge per unit time does not depend on N (4x the photons a disk, 1/4 the
/// iterations). At 0.01 the tests' 32x32 renders mostly improve too: relMSE on the caustic at
/// 256 → 1024 iterations 1.9e-3 → 4.9e-4 (vcm; 3.6e-3 → 1.1e-3 at 0.003), sppm at 128 → 512
/// iterations 4.4e-2 → 1.6e-2 (about 0.5 at 0.003); vcm on glass_room at 128 → 512 iterations
/// 4.1e-3 → 9.2e-4, against 3.3e-3 → 8.3e-4 at 0.003.
///
/// The wider disk pays less as the iterations grow: the squared bias falls as n^(2α − 2), the
/// variance as n^−α, so long renders become bias-bound (0.84 at 120 s against 0.77 at 30 s;
/// 0.015 lost most of its lead). That is what the H200 showed at 512x512 after some 450
/// iterations in 4 s (the table above); on such a GPU a render of thousands of iterations is
/// better served by 0.003 of the scene radius, a hardware GPU's default
/// ([`HARDWARE_GPU_RADIUS_FACTOR`]), or by a smaller `--alpha`. α = 2/3,
/// where the two rates meet, did not do better within 120 s.
///
/// Measured again when vcm came to end its camera subpaths at their first diffuse vertex
/// (build cdd2a5f, 256x256, 30 s, seed 11, `benches/merge_radius.sh`; ratio to 0.01's):
/// 0.0075 gave 1.02, 1.00 and 1.00 on tncg15_room, glass_room and cornell_box, 0.015 gave 1.12,
/// 1.20 and 1.19. So 0.01 stays.
pub const DEFAULT_RADIUS_FACTOR: f32 = 0.01;

/// The merge radius's default on a hardware GPU, as a share of the scene's bounding-sphere
/// radius: 0.003. Such a GPU runs tens to hundreds of times the iterations of the CPU backend in
/// the same time (an H200: some 1300 of vcm at 512x512 in 4 s, against 21 on 2 CPU cores in
/// 10 s), so its renders are long in iterations, and in long renders the squared bias of a wide
/// disk outlasts the variance it saves (see [`DEFAULT_RADIUS_FACTOR`]). Measured on an NVIDIA H200
/// (2026-11-27, vcm at its first diffuse vertex, seed 5, one render each, relMSE minus the
/// references' noise as a ratio of 0.003's to 0.01's; docs/bench/2026-11-27_h200/):
///
/// | H200 | tncg15_room | glass_room | cornell_box |
/// | --- | --- | --- | --- |
/// | 256x256, 6 s (about 3600 – 8400 iterations) | 1.07 | 0.68 | 0.87 |
/// | 512x512, 4 s (about 1200 – 2300 iterations) | 0.28 | 0.24 | 0.21 |
///
/// At 512x512, the default size, that makes vcm 0.26 of the GPU path tracer's relMSE by the
/// geometric mean over the three scenes, against 1.09 at 0.01. A software adapter (lavapipe)
/// runs about as many iterations as the CPU backend and keeps [`DEFAULT_RADIUS_FACTOR`].
pub const HARDWARE_GPU_RADIUS_FACTOR: f32 = 0.003;

/// The default initial radius of `vcm`, which merges within each vertex's clearance
/// ([`local_radius`]), as a share of the scene's bounding-sphere radius: 0.03 (the other merging
/// methods keep [`DEFAULT_RADIUS_FACTOR`]). Where surfaces meet, a disk that reaches across the
/// edge counts the photons of the wrong surface and misses the light behind it: at 0.02 of the
/// scene radius on tncg15_room, 89 % of the squared bias (in 4x4-pixel blocks) lay in 5 % of
/// the image, the room's edges and outlines. Within the clearance that bias is gone, and the
/// flat walls bear a disk three times as wide. Measured with a prototype of this change (which
/// read the floor from the environment at every vertex, some 7 % of its time; CPU, 256x256,
/// 30 s, 2 cores, seeds 11 and 12, relMSE against the H100 references with their noise):
///
/// | tncg15_room | relMSE | of it variance | of it squared bias and reference noise |
/// | --- | --- | --- | --- |
/// | 0.01, one radius everywhere (before) | 6.07e-4 | 4.17e-4 | 1.90e-4 |
/// | 0.01 within the clearance (floor 0.25) | 5.74e-4 | 5.07e-4 | 0.67e-4 |
/// | 0.02 within the clearance (floor 0.25) | 2.89e-4 | 2.09e-4 | 0.80e-4 |
/// | 0.025 (floor 0.1) | 2.37e-4 | 1.61e-4 | 0.76e-4 |
/// | 0.03 (floor 0.25) | 2.58e-4 | 1.24e-4 | 1.34e-4 |
/// | 0.03 (floor 0.1) | 2.24e-4 | 1.36e-4 | 0.88e-4 |
/// | 0.03 (floor 0.05) | 2.32e-4 | 1.45e-4 | 0.87e-4 |
/// | 0.03 (floor 0.02) | 2.54e-4 | 1.69e-4 | 0.85e-4 |
/// | 0.04 (floor 0.25) | 3.62e-4 | 1.01e-4 | 2.60e-4 |
///
/// (The reference's own noise is 0.66e-4.) On glass_room (seed 11) 0.03 within the clearance
/// gave 5.07e-4 against 7.98e-4 at 0.01 everywhere, on cornell_box 1.65e-4 against 1.63e-4.
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
/// `radius` (`vcm`, [`crate::transport::method::Method::merges_within_clearance`]): the vertex's clearance
/// (`crate::transport::clearance`), at most `radius` and at least [`CLEARANCE_FLOOR`] of it. Within its
/// clearance the disk lies on the vertex's own plane in front of every other surface, so the
/// merge is free of the bias where surfaces meet (the room's edges, an emitter's outline, what
/// stands on the floor), which held most of merging's bias (see [`VCM_RADIUS_FACTOR`]). The
/// schedule still shrinks it over iterations: consistent as before.
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
    // division need not give r / r = 1 (shaders/clearance.wgsl, the same step).
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
