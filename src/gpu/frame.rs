//! The host's view of what the kernels read and write: the uniform [`Frame`] of every dispatch
//! (`Frame` in `shaders/scene.wgsl`), one pass's [`PixelSums`], the workgroup and pass sizes,
//! and the word layout of the splat tallies (`shaders/splat.wgsl`).

use crate::layout::MAX_PLANAR_MIRRORS;
use crate::layout::{FlatScene, PlanarMirror};
use crate::transport::camera::Camera;
use crate::transport::faults::Faults;
use crate::transport::method::Method;
use bytemuck::{Pod, Zeroable};

/// One dispatch's parameters (`Frame` in `shaders/scene.wgsl`): the camera, which samples of
/// which tile, the method and its light pass, the film band, the test-only faults, and the
/// scene's planar mirrors (`planar_mirror`). A whole number of vec4s (`tests/layout.rs`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct Frame {
    pub camera: Camera,
    pub seed: u32,
    pub first_sample: u32,
    pub sample_count: u32,
    pub num_emitters: u32,
    pub tile_origin: [u32; 2],
    pub tile_size: [u32; 2],
    pub max_bounces: u32,
    pub specular_scale: f32,
    /// Shadow rays per diffuse vertex (`--light-samples`, at least 1).
    pub light_samples: u32,
    /// `Faults::grey_indirect` as 0 or 1 (test-only).
    pub grey_indirect: u32,
    /// `METHOD_*` in `shaders/scene.wgsl`: 0 path, 1 light, 2 bdpt, 3 sppm, 4 vcm, 5 vcm-full,
    /// 6 whitted, 7 photon-map, 8 radiosity.
    pub method: u32,
    /// N: light subpaths per iteration (one per pixel).
    pub n_light_paths: u32,
    /// The iteration's slot in the pass (its image sum).
    pub slot: u32,
    /// Light vertices the pool holds.
    pub vertex_capacity: u32,
    /// The light subpaths of a light-pass dispatch: `path_origin..path_origin + path_count`.
    pub path_origin: u32,
    pub path_count: u32,
    /// `Faults::importance_missing_cos` as 0 or 1 (test-only).
    pub importance_missing_cos: u32,
    /// τ of BDPT's Russian roulette on visibility rays (`cpu::shadow_probe::shadow_threshold_for`, which the caller passes in; 0: none).
    pub shadow_threshold: f32,
    /// Merging's MIS constants of the iteration (`subpath::MergeMis`; 0 but for SPPM and VCM).
    pub merge_vm: f32,
    pub merge_vc: f32,
    /// The merge kernel's normalisation 1 / (π r² N) of the iteration.
    pub merge_normalization: f32,
    /// The film band: the first image row the pass sums (and for the methods that splat, the
    /// splat tallies and camera radiance) hold, and how many rows; the whole image unless it is
    /// larger than one binding.
    pub film_row: u32,
    pub film_rows: u32,
    /// Pixels the band buffers hold (`film_rows` of the largest band times the width): the
    /// offset of the tallies' words after the splat cells.
    pub band_pixels: u32,
    /// The first light subpath of the wave (the pool's path heads are the wave's).
    pub wave_origin: u32,
    /// `Faults::continue_at_vanishing_density` as 0 or 1 (test-only).
    pub continue_at_vanishing_density: u32,
    /// τ of VCM's Russian roulette on merge queries (`subpath::MERGE_RR_THRESHOLD`; 0 but for
    /// VCM).
    pub merge_rr_threshold: f32,
    /// `Faults::merge_rr_undivided` as 0 or 1 (test-only).
    pub merge_rr_undivided: u32,
    /// How many of `planar_mirrors` the scene has (`planar_mirror::find`).
    pub planar_mirror_count: u32,
    /// `subpath::MergeMis::camera_goes_on` of the iteration as 0 or 1: whether the camera
    /// subpaths go on past their first diffuse vertex (1 but for SPPM and vcm that merges).
    pub camera_goes_on: u32,
    /// The iteration's merge radius r_i (0 but for SPPM and VCM).
    pub merge_radius: f32,
    /// Whether merges use each camera vertex's radius within its clearance (vcm,
    /// `Method::merges_within_clearance`) as 1, or r_i everywhere as 0, and the least share of
    /// r_i it leaves (`merging::CLEARANCE_FLOOR`).
    pub merges_within_clearance: u32,
    pub clearance_floor: f32,
    /// The view's reach (`MergeRadius::reach`): a camera vertex this far from the eye or
    /// farther merges within `merge_radius`, a nearer one within its share
    /// (`merging::footprint_share`; 0: every vertex within `merge_radius`).
    pub merge_reach: f32,
    /// `SamplerKind::code` of the film's sampler (`--sampler`).
    pub sampler: u32,
    /// Adaptive sampling (path tracing): the dispatch covers runs `run_offset..run_offset +
    /// run_count` of the pixel runs buffer instead of a tile (0: the tile, each pixel the
    /// frame's samples).
    pub run_offset: u32,
    pub run_count: u32,
    /// To the 16-byte boundary of `planar_mirrors`.
    pub pad4: u32,
    /// The scene's planar mirrors, for next-event estimation through them (BDPT).
    pub planar_mirrors: [PlanarMirror; MAX_PLANAR_MIRRORS as usize],
}

impl Frame {
    /// The frame of a new renderer: the whole image as one tile and one film band, no samples
    /// yet, the method's constants, τ, the planted faults and the scene's planar mirrors.
    pub fn first(
        scene: &FlatScene,
        camera: Camera,
        seed: u32,
        faults: Faults,
        method: Method,
        shadow_threshold: f32,
        vertex_capacity: u32,
    ) -> Frame {
        Frame {
            camera,
            seed,
            first_sample: 0,
            sample_count: 0,
            num_emitters: scene.emitters.len() as u32,
            tile_origin: [0, 0],
            tile_size: [camera.width, camera.height],
            max_bounces: faults.max_bounces,
            specular_scale: faults.specular_scale,
            light_samples: 1,
            grey_indirect: faults.grey_indirect as u32,
            method: match method {
                Method::Path => 0,
                Method::Light => 1,
                Method::Bdpt => 2,
                Method::Sppm => 3,
                Method::Vcm => 4,
                Method::VcmFull => 5,
                Method::Whitted => 6,
                Method::PhotonMap => 7,
                Method::Radiosity => 8,
            },
            n_light_paths: camera.width * camera.height,
            slot: 0,
            vertex_capacity,
            path_origin: 0,
            path_count: 0,
            importance_missing_cos: faults.importance_missing_cos as u32,
            shadow_threshold,
            merge_vm: 0.0,
            merge_vc: 0.0,
            merge_normalization: 0.0,
            film_row: 0,
            film_rows: camera.height,
            band_pixels: camera.width * camera.height,
            wave_origin: 0,
            continue_at_vanishing_density: faults.continue_at_vanishing_density as u32,
            merge_rr_threshold: if matches!(method, Method::Vcm | Method::VcmFull) {
                crate::transport::subpath::MERGE_RR_THRESHOLD
            } else {
                0.0
            },
            merge_rr_undivided: faults.merge_rr_undivided as u32,
            planar_mirror_count: scene.planar_mirrors.len() as u32,
            camera_goes_on: 1,
            merge_radius: 0.0,
            // Whether the method merges within the clearance; the iteration clears it where it
            // does not merge (`Bidirectional`).
            merges_within_clearance: (method.merges_within_clearance()
                && !faults.merge_ignores_clearance) as u32,
            clearance_floor: crate::transport::merging::CLEARANCE_FLOOR,
            merge_reach: 0.0,
            sampler: 0,
            run_offset: 0,
            run_count: 0,
            pad4: 0,
            planar_mirrors: std::array::from_fn(|i| {
                scene.planar_mirrors.get(i).copied().unwrap_or_default()
            }),
        }
    }
}

/// One pass's sums for one pixel (`PixelSums` in `shaders/scene.wgsl`), in f32: a pass holds
/// at most [`MAX_PASS_SPP`] samples, and the host folds it into the f64 film.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct PixelSums {
    pub sum: [f32; 3],
    pub n: f32,
    pub sum_sq: [f32; 3],
    pub dropped: f32,
    /// The sum and count of the finite samples of even index (`PixelStats::even_sum`).
    pub even_sum: [f32; 3],
    pub even_n: f32,
}

impl PixelSums {
    /// The pass's sums in f64, as one batch of unweighted samples.
    pub fn stats(&self) -> crate::film::PixelStats {
        let f = |v: [f32; 3]| v.map(f64::from);
        crate::film::PixelStats {
            sum: f(self.sum),
            sum_sq: f(self.sum_sq),
            n: self.n as u64,
            dropped: self.dropped as u64,
            even_sum: f(self.even_sum),
            even_n: self.even_n as u64,
            w: self.n as f64,
            w_sq: self.n as f64,
            even_w: self.even_n as f64,
        }
    }
}

/// Workgroup size of the kernel (8 x 8, `@workgroup_size` in `shaders/path.wgsl`).
pub const WORKGROUP: u32 = 8;

/// At most this many samples per pixel go into one pass's f32 sums before they are folded into
/// f64 on the host: the relative rounding error of an f32 sum of k terms is below k · 2^-24,
/// so 64 samples keep it under 4e-6 (`tests/precision.rs` measures the alternative, a running
/// f32 sum, at 10^5 samples).
pub const MAX_PASS_SPP: u32 = 64;

/// A dispatch should end within this time: drivers reset GPUs whose dispatches run for
/// seconds (wgpu #2554), and lavapipe's run at most ~0.5 s this way.
pub const TARGET_DISPATCH_SECONDS: f64 = 0.05;

/// A pass (or iteration) expected to run longer than this looks at a stop between its
/// dispatches, waiting for each (`GpuRenderer::stop_checked`): 0.25 s, the render loop's pass
/// target, so that short passes keep the queue full.
pub const STOP_LATENCY_SECONDS: f64 = 0.25;

/// Words of one tally cell (`CELL_WORDS` in `shaders/splat.wgsl`).
pub(super) const CELL_WORDS: u64 = 8;

/// Word offsets into the tallies (`shaders/splat.wgsl`) for an image of `pixels` pixels.
pub(super) fn image_cells_word(pixels: u64) -> u64 {
    pixels * CELL_WORDS
}
pub(super) fn vertex_counter_word(pixels: u64) -> u64 {
    (pixels + MAX_PASS_SPP as u64) * CELL_WORDS
}
pub(super) fn tally_words(pixels: u64) -> u64 {
    vertex_counter_word(pixels) + 1 + pixels
}
