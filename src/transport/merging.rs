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

use crate::accel::bvh::intersect_closest;
use crate::layout::{FlatScene, KIND_GLASS, KIND_MIRROR};
use crate::math::geometry::{offset_ray_origin, Ray};
use crate::transport::bsdf::{is_diffuse, reflect, refract};
use crate::transport::camera::Camera;
use crate::transport::method::Method;
use glam::Vec3;

// What sets the radius. Merging's bias is set by the disk's size in the scene where it lies,
// and what the image can resolve there is set by how far that is from the camera: a disk a
// fixed share of the view wide at a camera vertex x is
//
//   r_i(x) = k · tan(θ/2) · t(x) · i^((α − 1) / 2),
//
// with θ the vertical field of view and t(x) the distance along the camera subpath from the eye
// to x (through any mirrors and glass before it). Nothing the camera does not see enters it, and
// it scales with the scene. The share k does not depend on the image's size in pixels: a radius
// a few pixels wide would widen the disk in the scene as the image shrinks, and merging's bias
// with it (docs/journal/2026-11-27_merge_radius.md measured that and refuted it).
//
// The hash grid needs a largest radius per iteration: the radius at the view's reach T
// ([`view_reach`]), the distance that half of the view's first diffuse vertices lie within.
// Farther vertices merge within that largest radius, r_i(x) = r_i(T). So a render's
// radius is r_i (the largest, [`MergeRadius::at`]) and T ([`MergeRadius::reach`]); in sppm each
// vertex's is r_i · min(t(x) / T, 1) ([`footprint_share`]). vcm and vcm-full merge within r_i(T)
// at every vertex (reach 0), vcm further limited by the vertex's clearance ([`merge_share`]):
// at equal time that was below the scene-bound radius's error on all three reference scenes,
// and the share by distance was not (see [`VCM_VIEW_SHARE`]).

/// k for `vcm` (which merges within each vertex's clearance, [`local_radius`]), one radius at
/// every vertex: 0.031, a disk 0.0155 of the view's height at the view's reach (the height is
/// 2 tan(θ/2) T). On the reference scenes at 256x256 in 30 s on the CPU, seeds 21 – 24 in one
/// run, vcm's relMSE (the references' noise subtracted) was 0.984, 0.982 and 0.922 of that at a
/// radius of 0.03 of the scene's bounding-sphere radius on tncg15_room, glass_room and cornell_box; a share by distance, r_i · min(t / T, 1) at
/// k = 0.036, gave 1.062, 0.982 and 0.802 (docs/journal/2026-11-28_view_radius.md): the room
/// wants a wide disk near the camera. Where surfaces meet, a disk that reaches across the edge
/// counts the photons of the wrong surface and misses the light behind it; within the clearance
/// that bias is gone, and the flat walls bear a wide disk (docs/journal/2026-11-27_clearance.md).
pub const VCM_VIEW_SHARE: f32 = 0.031;

/// k for `sppm` and `vcm-full`: 0.012, a third of vcm's share by distance (0.036), since their
/// disks do not stop at the clearance (with radii as shares of the scene's bounding sphere,
/// SPPM's relMSE at 0.01 was 0.13 – 0.16 of that at 0.003: CPU, 256x256, 30 s;
/// docs/journal/2026-11-27_merge_radius.md). SPPM's relMSE at 30 s, seeds 21 and 22, was 1.075,
/// 1.001 and 1.093 of that at 0.01 of the scene radius on the three reference scenes; k is not
/// tuned further.
pub const DEFAULT_VIEW_SHARE: f32 = 0.012;

/// k for `photon-map`, whose radius is the same at every vertex and every iteration: 0.012, as
/// sppm's. On the reference scenes at 256x256 in 20 s on the CPU (seeds 21 and 22), half of it
/// had 0.98, 0.83 and 1.23 of its relMSE on tncg15_room, glass_room and cornell_box, the same by
/// the geometric mean; twice it 1.69, 1.27 and 1.13 (docs/records/2026-11-29_photon_map).
pub const PHOTON_MAP_VIEW_SHARE: f32 = 0.012;

/// The share of a radius that a hardware GPU takes by default: 0.3. Such a GPU runs tens to
/// hundreds of times the iterations of the CPU backend in the same time, and in long renders
/// the squared bias of a wide disk outlasts the variance it saves. On an NVIDIA H200 at 512x512
/// in 4 s (1200 – 2300 iterations), vcm's relMSE (the references' noise subtracted) at 0.3 of
/// the CPU's radius was 0.28, 0.24 and 0.21 of that at the CPU's on tncg15_room, glass_room and
/// cornell_box (docs/records/2026-11-27_h200/first_diffuse_radius_512.txt, when both were shares
/// of the scene's bounds). A software adapter (lavapipe) runs about as many iterations as the CPU
/// backend and keeps the CPU's radius.
pub const HARDWARE_GPU_RADIUS_SCALE: f32 = 0.3;

/// The least share of the iteration's radius that [`local_radius`] gives a vertex near another
/// surface: 0.1 (measured with vcm's radius a share of the scene's bounds). Without one, merges
/// at an edge would shrink to nothing; the MIS weights then give those paths to the connections,
/// which is right for most, but the paths that only merging samples (a caustic seen in a mirror)
/// would grow noisy there.
pub const CLEARANCE_FLOOR: f32 = 0.1;

/// The least share of the iteration's radius that [`footprint_share`] gives a vertex near the
/// camera: 0.01, so that the MIS constants of a vertex at the lens (η^−β grows as the fourth power
/// of the share's inverse) stay far inside f32.
pub const FOOTPRINT_FLOOR: f32 = 0.01;

/// The default α: SmallVCM's and Knaus and Zwicker's 0.75.
pub const DEFAULT_ALPHA: f32 = 0.75;

/// Rays per side of the grid over the image that [`view_reach`] traces.
pub const VIEW_PROBE_RAYS: u32 = 32;

/// The share of the probe's first diffuse vertices that lie within the view's reach: 0.5, the
/// median. At 0.9 (with k = 0.03) most of the image merged within less than the radius at the
/// reach, and vcm's relMSE on tncg15_room was 1.12 – 1.21 of the scene-bound radius's (seeds
/// 11 – 13); the median keeps the nearer half of the view alone merging within less.
pub const VIEW_REACH_QUANTILE: f64 = 0.5;

/// Mirror and glass bounces [`view_reach`] follows to a diffuse vertex.
const VIEW_PROBE_BOUNCES: u32 = 16;

/// The most light subpaths N an iteration of the merging methods traces by default: 2^18, one
/// per pixel up to a 512x512 image. The radius is a share of the view, not of a pixel, so the
/// photons a disk gathers, and merging's noise, depend on N and not on the image's size; what
/// grows with the image is the camera pass. A merge reads every light vertex of the iteration,
/// so on the GPU each further wave of the vertex pool costs a camera pass over the whole image:
/// with N bounded, the waves per iteration are bounded too, and an iteration's cost grows as its
/// pixels. 2^18 subpaths of a closed room store about 1 million vertices, one wave within
/// lavapipe's 128 MiB binding (80 bytes each).
pub const MAX_LIGHT_PATHS: u32 = 1 << 18;

/// The most light subpaths N an iteration of light tracing and BDPT traces by default: 2^20,
/// one per pixel up to a megapixel. Their connections to the camera splat anywhere in the
/// image, so on a GPU whose binding cannot hold every pixel's splat tally at once, each film
/// band of b pixels traces all N subpaths again (`GpuRenderer::for_each_film_band`): an image
/// of P pixels then costs about (P / b + 1) · N subpaths an iteration, at most 2 P with N <= b.
/// A band of lavapipe's 128 MiB binding holds 3.7 million pixels, so with N bounded so an
/// iteration's cost grows as its pixels on every device; beyond a megapixel, pixels share light
/// subpaths (pixel index mod N) as the merging methods' do beyond [`MAX_LIGHT_PATHS`].
pub const MAX_CONNECTED_LIGHT_PATHS: u32 = 1 << 20;

/// N, the light subpaths per iteration of `method` on an image of `pixels`: `requested` if given
/// (`--light-paths`), else one per pixel, at most [`MAX_LIGHT_PATHS`] for the merging methods
/// and [`MAX_CONNECTED_LIGHT_PATHS`] for light tracing and BDPT; never more than the pixels.
/// Pixel j's camera subpaths connect to light subpath j mod N.
pub fn light_paths(method: Method, pixels: u64, requested: Option<u32>) -> u32 {
    let per_pixel = pixels.min(u32::MAX as u64) as u32;
    let most = if method.merges() {
        MAX_LIGHT_PATHS
    } else {
        MAX_CONNECTED_LIGHT_PATHS
    };
    requested
        .unwrap_or_else(|| per_pixel.min(most))
        .clamp(1, per_pixel.max(1))
}

/// The merge radius of a render: its largest radius r_1 in scene units, α, and the view's reach
/// T at which a vertex takes the largest radius (0: every vertex takes it); with N, the light
/// subpaths an iteration merges with (`light_paths`: None, the default of [`light_paths`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergeRadius {
    pub initial: f32,
    pub alpha: f32,
    pub reach: f32,
    pub light_paths: Option<u32>,
}

impl MergeRadius {
    /// The same radius r_1 at every vertex (`--radius`).
    pub fn uniform(initial: f32, alpha: f32) -> MergeRadius {
        MergeRadius {
            initial,
            alpha,
            reach: 0.0,
            light_paths: None,
        }
    }

    /// The largest radius of iteration `iteration` (counted from 0, so the first is r_1).
    #[inline]
    pub fn at(&self, iteration: u32) -> f32 {
        let i = iteration as f64 + 1.0;
        (self.initial as f64 * i.powf((self.alpha as f64 - 1.0) * 0.5)) as f32
    }

    /// The default of `method` for what `camera` sees of `scene`: the disk k · tan(θ/2) · T wide
    /// at the view's reach T ([`view_reach`]; k [`VCM_VIEW_SHARE`] for vcm, [`DEFAULT_VIEW_SHARE`]
    /// for sppm and vcm-full), α = [`DEFAULT_ALPHA`]. SPPM's nearer vertices merge within
    /// k · tan(θ/2) · t(x). vcm and vcm-full merge within the radius at T at every vertex: vcm's
    /// error was lower so (see [`VCM_VIEW_SHARE`]), and vcm-full's paths may merge at any of their
    /// diffuse vertices, whose MIS weights carry one η for all of them
    /// (`crate::transport::subpath`, "A radius of the vertex").
    pub fn default_for(scene: &FlatScene, camera: &Camera, method: Method) -> MergeRadius {
        let k = if method.merges_within_clearance() {
            VCM_VIEW_SHARE
        } else if method == Method::PhotonMap {
            PHOTON_MAP_VIEW_SHARE
        } else {
            DEFAULT_VIEW_SHARE
        };
        let reach = view_reach(scene, camera);
        MergeRadius {
            initial: k * Vec3::from(camera.up).length() * reach,
            // photon-map's radius is fixed (α = 1): not progressive.
            alpha: if method.progressive() {
                DEFAULT_ALPHA
            } else {
                1.0
            },
            reach: if method == Method::Sppm { reach } else { 0.0 },
            light_paths: None,
        }
    }

    /// N of `method` on an image of `pixels` ([`light_paths`]); BDPT's at radius 0 (vcm is then
    /// BDPT).
    pub fn light_paths_for(&self, method: Method, pixels: u64) -> u32 {
        let method = if self.initial > 0.0 {
            method
        } else {
            Method::Bdpt
        };
        light_paths(method, pixels, self.light_paths)
    }

    /// This radius at [`HARDWARE_GPU_RADIUS_SCALE`] of r_1, α and the reach kept.
    pub fn for_hardware_gpu(self) -> MergeRadius {
        MergeRadius {
            initial: self.initial * HARDWARE_GPU_RADIUS_SCALE,
            ..self
        }
    }
}

/// The view's reach T: the distance along the camera subpath to the first diffuse vertex
/// (through mirrors and glass, glass refracting where it can) that [`VIEW_REACH_QUANTILE`] of the
/// rays through a [`VIEW_PROBE_RAYS`]² grid over the image lie within. A function of what the
/// camera sees alone, in scene units; the scene's bounding-sphere radius where no probe ray meets
/// a diffuse surface (the image is then black or shows emitters only).
pub fn view_reach(scene: &FlatScene, camera: &Camera) -> f32 {
    let n = VIEW_PROBE_RAYS;
    let mut depths = Vec::with_capacity((n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let sx = 2.0 * (i as f32 + 0.5) / n as f32 - 1.0;
            let sy = 1.0 - 2.0 * (j as f32 + 0.5) / n as f32;
            let d = Vec3::from(camera.forward)
                + sx * Vec3::from(camera.right)
                + sy * Vec3::from(camera.up);
            let ray = Ray {
                o: Vec3::from(camera.eye),
                d: d.normalize(),
            };
            depths.extend(first_diffuse_depth(scene, ray));
        }
    }
    if depths.is_empty() {
        return scene_radius(scene);
    }
    depths.sort_by(f32::total_cmp);
    let k = ((depths.len() as f64 * VIEW_REACH_QUANTILE).ceil() as usize).clamp(1, depths.len());
    depths[k - 1]
}

/// The distance along `ray` and the mirror and glass bounces after it to the first diffuse
/// vertex, or None if it leaves the scene or bounces too often first.
fn first_diffuse_depth(scene: &FlatScene, mut ray: Ray) -> Option<f32> {
    let mut depth = 0.0;
    for _ in 0..VIEW_PROBE_BOUNCES {
        let hit = intersect_closest(scene, &ray, f32::MAX)?;
        depth += hit.t;
        let material = &scene.materials[hit.material as usize];
        let wo = -ray.d;
        let wi = match material.kind {
            KIND_MIRROR => reflect(wo, hit.n),
            KIND_GLASS => match refract(wo, hit.n, material.ior) {
                Some((wt, _)) => wt,
                None => reflect(wo, hit.n),
            },
            // A diffuse vertex ends the camera subpath's way to its first merge; a black
            // emitter ends the subpath.
            _ => return is_diffuse(material).then_some(depth),
        };
        ray = Ray {
            o: offset_ray_origin(hit.p, hit.p_err, hit.n, wi),
            d: wi,
        };
    }
    None
}

/// A camera vertex's share of the iteration's largest radius by its distance `t` along the
/// camera subpath: min(t / `reach`, 1), at least [`FOOTPRINT_FLOOR`]; 1 where the radius is
/// uniform (`reach` 0).
#[inline]
pub fn footprint_share(t: f32, reach: f32) -> f32 {
    if reach <= 0.0 {
        return 1.0;
    }
    (t / reach).clamp(FOOTPRINT_FLOOR, 1.0)
}

/// The merge radius at a camera vertex `p` on primitive `prim` of an iteration that merges within
/// `radius` (`vcm`, [`Method::merges_within_clearance`]): the vertex's clearance
/// (`crate::transport::clearance`), at most `radius` and at least [`CLEARANCE_FLOOR`] of it.
/// Within its clearance the disk lies on the vertex's own plane in front of every other surface,
/// so the merge is free of the bias where surfaces meet (the room's edges, an emitter's outline,
/// what stands on the floor), which held most of merging's bias (see [`VCM_VIEW_SHARE`]). The
/// schedule shrinks it over iterations, so the estimate stays consistent.
pub fn local_radius(scene: &FlatScene, p: Vec3, prim: u32, radius: f32) -> f32 {
    crate::transport::clearance::clearance(scene, p, prim, radius).max(CLEARANCE_FLOOR * radius)
}

/// The merge radius at camera vertex `p` on primitive `prim` as a share of the iteration's
/// largest `radius`: the vertex's `footprint` ([`footprint_share`]) of it, limited by the
/// clearance ([`local_radius`]) where the method merges `within_clearance`. Every strategy of a
/// path through the vertex weighs the merge there with this radius (`MergeMis::within`;
/// `crate::transport::subpath`, "A radius of the vertex").
pub fn merge_share(
    scene: &FlatScene,
    p: Vec3,
    prim: u32,
    radius: f32,
    footprint: f32,
    within_clearance: bool,
) -> f32 {
    if !within_clearance {
        return footprint;
    }
    let own = footprint * radius;
    // Where the clearance reaches the radius the share is the footprint exactly, on both
    // backends: WGSL's division need not give r / r = 1 (shaders/merging.wgsl, the same step).
    let local = local_radius(scene, p, prim, own);
    if local >= own {
        footprint
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
        let r = MergeRadius::uniform(2.0, 0.75);
        assert_eq!(r.at(0), 2.0);
        // r_4 = r_1 · 4^(−1/8).
        assert!((r.at(3) - 2.0 * 4f32.powf(-0.125)).abs() < 1e-6);
        assert!(r.at(100) < r.at(99));
    }

    #[test]
    fn a_vertex_merges_within_its_share_of_the_largest_radius_by_distance() {
        // Half way to the reach: half the radius; past it, all of it; at the eye, the floor.
        assert_eq!(footprint_share(5.0, 10.0), 0.5);
        assert_eq!(footprint_share(30.0, 10.0), 1.0);
        assert_eq!(footprint_share(0.0, 10.0), FOOTPRINT_FLOOR);
        // A uniform radius (reach 0) is all of it everywhere.
        assert_eq!(footprint_share(0.5, 0.0), 1.0);
    }
}
