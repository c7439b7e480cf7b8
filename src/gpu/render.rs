//! The GPU backend's work: upload the flattened scene as it is, compile the path-tracing
//! kernel, run it in bounded dispatches, and fold each pass's sums into the f64 film.

use super::bidirectional::Bidirectional;
use super::shader::{ArrayLengths, Residency};
use crate::camera::Camera;
use crate::cpu::Faults;
use crate::film::Film;
use crate::flat::{FlatScene, PlanarMirror};
use crate::method::Method;
use crate::planar_mirror::MAX_PLANAR_MIRRORS;
use anyhow::{anyhow, bail, Context, Result};
use bytemuck::{Pod, Zeroable};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use wgpu::util::DeviceExt;

/// One dispatch's parameters (`Frame` in `shaders/scene.wgsl`): the camera, which samples of
/// which tile, the method and its light pass, the film band, the test-only faults, and the
/// scene's planar mirrors (`planar_mirror`). Twenty-four vec4s.
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
    /// `METHOD_*` in `shaders/scene.wgsl`: 0 path, 1 light, 2 bdpt, 3 sppm, 4 vcm.
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
    /// τ of BDPT's Russian roulette on visibility rays (`subpath::shadow_threshold`; 0: none).
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
    pub pad0: u32,
    /// The scene's planar mirrors, for next-event estimation through them (BDPT).
    pub planar_mirrors: [PlanarMirror; MAX_PLANAR_MIRRORS as usize],
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

/// How the kernel is compiled: with naga's runtime checks (bounds checks and loop bounding,
/// wgpu's default since 25) or without (`create_shader_module_trusted`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Checks {
    Checked,
    Unchecked,
}

/// The GPU renderer for one scene, camera, seed and method.
pub struct GpuRenderer {
    pub(super) device: wgpu::Device,
    pub(super) queue: wgpu::Queue,
    /// Path tracing's kernel (None for light tracing and BDPT).
    pipeline: Option<wgpu::ComputePipeline>,
    pub(super) bind_group: wgpu::BindGroup,
    pub(super) frame_buffer: wgpu::Buffer,
    pub(super) sums: wgpu::Buffer,
    pub(super) readback: wgpu::Buffer,
    /// Image rows per film band: the pass sums of path tracing cover this many rows at a time,
    /// so that any image renders within the device's largest binding; the whole image for the
    /// other methods (`check_image_fits`).
    film_rows: u32,
    pub(super) frame: Frame,
    pub(super) method: Method,
    /// Light tracing and BDPT: their kernels and buffers.
    pub(super) bidirectional: Option<Bidirectional>,
    /// The dispatch size, in camera paths, that should take about TARGET_DISPATCH_SECONDS;
    /// measured and updated after every pass.
    pub(super) paths_per_dispatch: u64,
    lost: Arc<(AtomicBool, Mutex<String>)>,
    #[cfg(feature = "stage-times")]
    pub(super) stage_times: super::stage_times::StageTimes,
}

#[cfg(feature = "stage-times")]
impl Drop for GpuRenderer {
    fn drop(&mut self) {
        if !self.stage_times.is_empty() {
            eprintln!("{} {}", self.method, self.stage_times.report());
        }
    }
}

/// Uploads one scene array as it is laid out on the host.
fn upload<T: Pod>(
    device: &wgpu::Device,
    residency: Residency,
    label: &str,
    data: &[T],
) -> wgpu::Buffer {
    // wgpu refuses zero-sized bindings: an empty array (a scene without spheres) is one zeroed
    // element that nothing references.
    let zero = [T::zeroed()];
    let data: &[T] = if data.is_empty() { &zero } else { data };
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(data),
        usage: match residency {
            Residency::Storage => wgpu::BufferUsages::STORAGE,
            Residency::Uniform => wgpu::BufferUsages::UNIFORM,
        },
    })
}

/// The primitive references packed four to a vec4<u32>, as both residencies declare them (the
/// BVH build pads `prims` to a multiple of four with `PRIM_PADDING`; only an empty scene's
/// array is zero-filled here).
fn packed_prims(scene: &FlatScene) -> Vec<[u32; 4]> {
    scene
        .prims
        .chunks(4)
        .map(|c| {
            let mut v = [0u32; 4];
            v[..c.len()].copy_from_slice(c);
            v
        })
        .collect()
}

/// The lengths the uniform residency declares.
pub fn array_lengths(scene: &FlatScene) -> ArrayLengths {
    ArrayLengths {
        triangles: scene.triangles.len(),
        spheres: scene.spheres.len(),
        materials: scene.materials.len(),
        emitters: scene.emitters.len(),
        nodes: scene.nodes.len(),
        prims: scene.prims.len().div_ceil(4),
        stack_size: crate::bvh::stack_size(&scene.nodes),
    }
}

/// The scene arrays the kernel binds, by name, with their sizes in bytes as uploaded.
pub fn scene_arrays(scene: &FlatScene) -> [(&'static str, usize); 6] {
    // An empty array is uploaded as one zeroed element (`upload`).
    let at_least = |bytes: usize, one: usize| bytes.max(one);
    [
        (
            "triangles",
            at_least(std::mem::size_of_val(&scene.triangles[..]), 64),
        ),
        (
            "spheres",
            at_least(std::mem::size_of_val(&scene.spheres[..]), 32),
        ),
        (
            "materials",
            at_least(std::mem::size_of_val(&scene.materials[..]), 32),
        ),
        (
            "emitters",
            at_least(std::mem::size_of_val(&scene.emitters[..]), 16),
        ),
        (
            "nodes",
            at_least(std::mem::size_of_val(&scene.nodes[..]), 128),
        ),
        ("prims", at_least(16 * scene.prims.len().div_ceil(4), 16)),
    ]
}

/// Bytes of one pixel's pass sums on the device.
const PIXEL_SUMS_BYTES: u64 = std::mem::size_of::<PixelSums>() as u64;

/// The largest buffer the device binds as storage.
pub(super) fn largest_binding(limits: &wgpu::Limits) -> u64 {
    limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size)
}

/// Whether a `width` x `height` render with `method` fits this device's largest storage
/// binding; if not, a sentence for the user. The per-pixel buffers are cut into film bands of
/// whole rows (path tracing: `GpuRenderer::film_rows`; the methods that splat: the band of
/// their tallies, `bidirectional::splat_band_rows`), so any image whose single row fits
/// renders: on lavapipe's 128 MiB, rows of up to 3.7 million pixels.
pub fn check_image_fits(
    limits: &wgpu::Limits,
    method: Method,
    width: u32,
    height: u32,
) -> Result<(), String> {
    let limit = largest_binding(limits);
    let fits = if method.splats() {
        super::bidirectional::splat_band_rows(limit, width, height).is_some()
    } else {
        width as u64 * PIXEL_SUMS_BYTES <= limit
    };
    if fits {
        return Ok(());
    }
    Err(format!(
        "one {width}-pixel row of a render with --method {method} needs more than this adapter \
         binds in one buffer ({limit} bytes); render it narrower, or with --backend cpu"
    ))
}

/// Whether every scene array fits one binding of `residency` on a device with `limits`; if not,
/// a sentence for the user naming the array, its size, the limit and what works instead.
pub fn check_scene_fits(
    limits: &wgpu::Limits,
    residency: Residency,
    scene: &FlatScene,
) -> Result<(), String> {
    let (limit, what) = match residency {
        Residency::Storage => (largest_binding(limits), "storage buffer binding"),
        Residency::Uniform => (
            limits
                .max_uniform_buffer_binding_size
                .min(limits.max_buffer_size),
            "uniform buffer binding",
        ),
    };
    for (name, bytes) in scene_arrays(scene) {
        if bytes as u64 > limit {
            let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
            let alternative = match residency {
                Residency::Uniform => "--scene-residency storage, or --backend cpu",
                Residency::Storage => "--backend cpu (no such limit)",
            };
            return Err(format!(
                "the scene's {name} array is {:.1} MiB ({} triangles), more than this adapter's \
                 largest {what} of {:.3} MiB (lavapipe's storage limit is 128 MiB, about 2 \
                 million triangles); render it with {alternative}, or use fewer triangles",
                mib(bytes as u64),
                scene.triangles.len(),
                mib(limit)
            ));
        }
    }
    Ok(())
}

impl Residency {
    /// Uniform buffers on CPU adapters (lavapipe, llvmpipe) when every array fits the device's
    /// uniform binding limit; storage buffers otherwise. Real GPUs get storage buffers: their
    /// uniform (constant) caches serialise divergent indices, which BVH traversal has.
    pub fn preferred(info: &wgpu::AdapterInfo, limits: &wgpu::Limits, scene: &FlatScene) -> Self {
        let max = limits.max_uniform_buffer_binding_size as usize;
        if info.device_type == wgpu::DeviceType::Cpu
            && scene_arrays(scene).iter().all(|&(_, s)| s <= max)
        {
            Residency::Uniform
        } else {
            Residency::Storage
        }
    }
}

/// A compute pipeline for entry point `entry` of the kernel, over bind groups of `layouts`.
pub(super) fn compute_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layouts: &[&wgpu::BindGroupLayout],
    entry: &str,
) -> wgpu::ComputePipeline {
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(|l| Some(*l)).collect();
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(entry),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(&pipeline_layout),
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// Bind-group entries 0, 1, … for whole buffers, in order.
pub(super) fn buffer_entries<'a>(
    buffers: impl Iterator<Item = &'a wgpu::Buffer>,
) -> Vec<wgpu::BindGroupEntry<'a>> {
    buffers
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect()
}

/// The bindings of `shaders/scene.wgsl`: the six scene arrays (storage or uniform), the frame
/// (uniform), the pass sums (read-write storage).
fn bind_group_layout(device: &wgpu::Device, residency: Residency) -> wgpu::BindGroupLayout {
    let buffer = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let scene_array = match residency {
        Residency::Storage => wgpu::BufferBindingType::Storage { read_only: true },
        Residency::Uniform => wgpu::BufferBindingType::Uniform,
    };
    let read_write = wgpu::BufferBindingType::Storage { read_only: false };
    let mut entries: Vec<_> = (0..6).map(|b| buffer(b, scene_array)).collect();
    entries.push(buffer(6, wgpu::BufferBindingType::Uniform));
    entries.push(buffer(7, read_write));
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("scene"),
        entries: &entries,
    })
}

impl GpuRenderer {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &FlatScene,
        camera: Camera,
        seed: u32,
        faults: Faults,
        checks: Checks,
        residency: Residency,
        method: Method,
    ) -> Result<GpuRenderer> {
        // A scene array beyond the binding limit would be a wgpu validation panic: say so first.
        check_scene_fits(&device.limits(), residency, scene).map_err(anyhow::Error::msg)?;
        let (width, height) = (camera.width, camera.height);
        let lost = Arc::new((AtomicBool::new(false), Mutex::new(String::new())));
        {
            let lost = lost.clone();
            device.set_device_lost_callback(move |reason, msg| {
                *lost.1.lock().unwrap() = format!("{reason:?}: {msg}");
                lost.0.store(true, Ordering::SeqCst);
            });
        }

        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let source = super::shader::source(residency, array_lengths(scene));
        let desc = wgpu::ShaderModuleDescriptor {
            label: Some("hexray path tracer"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        };
        let module = match checks {
            Checks::Checked => device.create_shader_module(desc),
            // SAFETY: the kernel's loops all terminate (BVH traversal visits each node at most
            // once; the path loop ends by Russian roulette with probability >= 0.05 per bounce
            // after bounce 3; the sample loop is counted), and every index is in bounds by
            // construction (node, primitive and material indices come from the flattened scene,
            // pixel indices are checked against the tile).
            Checks::Unchecked => unsafe {
                device.create_shader_module_trusted(desc, wgpu::ShaderRuntimeChecks::unchecked())
            },
        };
        let layout = bind_group_layout(device, residency);
        let (pipeline, bidirectional) = if method.splats() {
            let b = Bidirectional::new(
                device,
                &module,
                &layout,
                method,
                scene,
                &camera,
                faults.merge_kernel_ball,
            )?;
            (None, Some(b))
        } else {
            (
                Some(compute_pipeline(device, &module, &[&layout], "render")),
                None,
            )
        };
        if let Some(e) = pollster::block_on(scope.pop()) {
            bail!("the GPU rejected the {method} kernel: {e}");
        }

        let frame = Frame {
            camera,
            seed,
            first_sample: 0,
            sample_count: 0,
            num_emitters: scene.emitters.len() as u32,
            tile_origin: [0, 0],
            tile_size: [width, height],
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
            },
            n_light_paths: width * height,
            slot: 0,
            vertex_capacity: bidirectional.as_ref().map_or(0, |b| b.capacity),
            path_origin: 0,
            path_count: 0,
            importance_missing_cos: faults.importance_missing_cos as u32,
            shadow_threshold: if method.connects() {
                crate::subpath::shadow_threshold(scene, &camera)
            } else {
                0.0
            },
            merge_vm: 0.0,
            merge_vc: 0.0,
            merge_normalization: 0.0,
            film_row: 0,
            film_rows: height,
            band_pixels: width * height,
            wave_origin: 0,
            continue_at_vanishing_density: faults.continue_at_vanishing_density as u32,
            merge_rr_threshold: if matches!(method, Method::Vcm | Method::VcmFull) {
                crate::subpath::MERGE_RR_THRESHOLD
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
            clearance_floor: crate::merging::CLEARANCE_FLOOR,
            pad0: 0,
            planar_mirrors: std::array::from_fn(|i| {
                scene.planar_mirrors.get(i).copied().unwrap_or_default()
            }),
        };
        let frame_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("frame"),
            contents: bytemuck::bytes_of(&frame),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        // Path tracing's film bands: as many rows as one binding holds (`check_image_fits` has
        // made sure a row fits, and for the other methods the whole image).
        let film_rows = if let Some(b) = &bidirectional {
            b.band_rows
        } else {
            (largest_binding(&device.limits()) / (width as u64 * PIXEL_SUMS_BYTES))
                .clamp(1, height as u64) as u32
        };
        let sums_size = film_rows as u64 * width as u64 * PIXEL_SUMS_BYTES;
        let sums = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pixel sums"),
            size: sums_size,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pixel sums readback"),
            size: sums_size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let buffers = [
            upload(device, residency, "triangles", &scene.triangles),
            upload(device, residency, "spheres", &scene.spheres),
            upload(device, residency, "materials", &scene.materials),
            upload(device, residency, "emitters", &scene.emitters),
            upload(device, residency, "bvh nodes", &scene.nodes),
            upload(device, residency, "primitive refs", &packed_prims(scene)),
        ];
        let mut entries = buffer_entries(buffers.iter());
        entries.push(wgpu::BindGroupEntry {
            binding: 6,
            resource: frame_buffer.as_entire_binding(),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 7,
            resource: sums.as_entire_binding(),
        });
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &layout,
            entries: &entries,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            bail!("binding the scene failed: {e}");
        }
        Ok(GpuRenderer {
            device: device.clone(),
            queue: queue.clone(),
            pipeline,
            bind_group,
            frame_buffer,
            sums,
            readback,
            film_rows,
            frame,
            method,
            bidirectional,
            paths_per_dispatch: 1 << 16,
            lost,
            #[cfg(feature = "stage-times")]
            stage_times: Default::default(),
        })
    }

    pub(super) fn check_device(&self) -> Result<()> {
        if self.lost.0.load(Ordering::SeqCst) {
            bail!("the GPU device was lost ({})", self.lost.1.lock().unwrap());
        }
        Ok(())
    }

    /// Shadow rays per diffuse vertex (`--light-samples`; 1 unless set).
    pub fn set_light_samples(&mut self, n: u32) {
        self.frame.light_samples = n.max(1);
    }

    /// Adds samples `first..first + count` of every pixel to `film`. The samples are split into
    /// passes of at most MAX_PASS_SPP, each pass into dispatches of about `paths_per_dispatch`
    /// paths (whole rows of pixels times a number of samples); after each pass its f32 sums are
    /// read back and folded into the f64 film. If the device fails, the film keeps every pass
    /// completed before, and the error says what happened.
    pub fn render(&mut self, first: u32, count: u32, film: &mut Film) -> Result<()> {
        crate::render::check_film_for(self.method, film)?;
        let mut done = 0;
        while done < count {
            let n = (count - done).min(MAX_PASS_SPP);
            if self.method.splats() {
                self.pass_bidirectional(first + done, n, film)?;
            } else {
                self.pass(first + done, n, film)?;
            }
            done += n;
        }
        Ok(())
    }

    fn pass(&mut self, first: u32, count: u32, film: &mut Film) -> Result<()> {
        self.check_device()?;
        let (w, h) = (self.frame.camera.width, self.frame.camera.height);
        let start = Instant::now();
        self.for_each_film_band(film, self.film_rows, |a, z| {
            self.dispatch_band(first, count, a, z)
        })?;

        // Size the next dispatches from this pass's throughput.
        let image = (w as u64) * (h as u64);
        let paths_per_second = (image * count as u64) as f64 / start.elapsed().as_secs_f64();
        self.paths_per_dispatch =
            ((paths_per_second * TARGET_DISPATCH_SECONDS) as u64).clamp(4096, 1 << 28);
        Ok(())
    }

    /// Film bands of `rows` rows (the whole image unless its per-pixel buffers are larger than
    /// one binding), in turn: clears the pass sums, queues `work(band_start, band_end)`, reads
    /// the band's sums back and folds them into the film in f64.
    pub(super) fn for_each_film_band(
        &self,
        film: &mut Film,
        rows: u32,
        mut work: impl FnMut(u32, u32),
    ) -> Result<()> {
        let h = self.frame.camera.height;
        let mut band_start = 0;
        while band_start < h {
            let band_end = (band_start + rows).min(h);
            let mut encoder = self.device.create_command_encoder(&Default::default());
            encoder.clear_buffer(&self.sums, 0, None);
            self.queue.submit([encoder.finish()]);
            work(band_start, band_end);
            let mut encoder = self.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(&self.sums, 0, &self.readback, 0, None);
            self.queue.submit([encoder.finish()]);
            self.fold_sums(film, band_start, band_end - band_start)?;
            band_start = band_end;
        }
        Ok(())
    }

    /// Queues samples `first..first + count` of rows `band_start..band_end` (one film band) in
    /// dispatches of about `paths_per_dispatch` paths, each of all `count` samples over as many
    /// rows as that allows (a multiple of the workgroup height, at least one workgroup): the
    /// lanes then have `count` samples each to regenerate their paths with (`render` in
    /// `shaders/path.wgsl`). On lavapipe, 256x256, 64 spp, this gave 1.4 - 1.7x the camera
    /// paths/s of dispatches of one sample over more rows (docs/gpu.md). The smallest dispatch,
    /// one workgroup of rows with 64 samples, can exceed the time target on a slow adapter
    /// (about 0.5 s at 256 pixels wide on lavapipe, which has no watchdog); a real GPU's budget
    /// holds many such dispatches.
    fn dispatch_band(&self, first: u32, count: u32, band_start: u32, band_end: u32) {
        let w = self.frame.camera.width;
        let r = (self.paths_per_dispatch / (w as u64 * count.max(1) as u64)).max(1) as u32;
        let rows = (r.div_ceil(WORKGROUP) * WORKGROUP).min(band_end - band_start);
        let mut y = band_start;
        while y < band_end {
            let rows = rows.min(band_end - y);
            let frame = Frame {
                first_sample: first,
                sample_count: count,
                tile_origin: [0, y],
                tile_size: [w, rows],
                film_row: band_start,
                film_rows: band_end - band_start,
                ..self.frame
            };
            // One submission per dispatch: the uniform write lands before this dispatch and
            // after the previous one.
            self.queue
                .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&frame));
            let mut encoder = self.device.create_command_encoder(&Default::default());
            {
                let mut cpass = encoder.begin_compute_pass(&Default::default());
                cpass.set_pipeline(self.pipeline.as_ref().expect("path tracing's kernel"));
                cpass.set_bind_group(0, &self.bind_group, &[]);
                cpass.dispatch_workgroups(w.div_ceil(WORKGROUP), rows.div_ceil(WORKGROUP), 1);
            }
            self.queue.submit([encoder.finish()]);
            y += rows;
        }
    }

    /// Rows per film band (tests: a band of a few rows exercises the split on a small image),
    /// at least one and at most the buffers hold.
    pub fn set_film_rows(&mut self, rows: u32) {
        self.film_rows = rows.clamp(1, self.film_rows);
        if let Some(b) = &mut self.bidirectional {
            b.band_rows = self.film_rows;
            b.band_pixels = self.film_rows as u64 * self.frame.camera.width as u64;
        }
    }

    /// Reads the pass's sums back (copied to `readback` by the queued work) and folds them into
    /// the film in f64: rows `first_row..first_row + rows`.
    pub(super) fn fold_sums(&self, film: &mut Film, first_row: u32, rows: u32) -> Result<()> {
        let bytes = self.read_buffer(&self.readback)?;
        let sums: Vec<PixelSums> = bytemuck::pod_collect_to_vec(&bytes);
        let w = film.width as usize;
        let band = &mut film.pixels[first_row as usize * w..(first_row + rows) as usize * w];
        for (p, s) in band.iter_mut().zip(&sums) {
            for c in 0..3 {
                p.sum[c] += s.sum[c] as f64;
                p.sum_sq[c] += s.sum_sq[c] as f64;
            }
            p.n += s.n as u64;
            p.dropped += s.dropped as u64;
        }
        Ok(())
    }

    /// Maps a MAP_READ buffer after the queued work, copies its bytes out, unmaps it.
    pub(super) fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| anyhow!("waiting for the GPU: {e}"))?;
        self.check_device()?;
        rx.recv()
            .context("the GPU never answered the readback")?
            .map_err(|e| anyhow!("reading back from the GPU: {e}"))?;
        let bytes = slice
            .get_mapped_range()
            .map_err(|e| anyhow!("mapping the readback: {e}"))?
            .to_vec();
        buffer.unmap();
        Ok(bytes)
    }
}
