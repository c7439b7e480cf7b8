//! The GPU's light-subpath methods (light, bdpt, sppm, vcm, vcm-full, photon-map): the host side of `shaders/light_path.wgsl`,
//! `shaders/bdpt.wgsl` and the resolve pass of `shaders/film.wgsl`.
//!
//! Each iteration is a sequence of dispatches over the same buffers, as on the CPU
//! (`cpu::render_iterations`): the light pass traces N light subpaths (one per pixel, at most
//! `merging::MAX_LIGHT_PATHS` or `MAX_CONNECTED_LIGHT_PATHS`; `merging::light_paths`), splatting their connections to the camera into
//! order-independent fixed-point tallies and (BDPT) storing their diffuse vertices in a pool;
//! the camera pass traces one camera subpath per pixel and connects it to light subpath (pixel
//! index mod N); the resolve pass adds each pixel's camera radiance and splats as one sample,
//! and the image's sum for the iteration's batch mean.
//!
//! The pool holds the vertices of one *wave* of light subpaths (whole rows' worth):
//! BDPT runs the light and camera passes wave by wave, so any image fits a pool of bounded size.
//! Waves are sized from the vertices per subpath measured so far. A wave that asks for more
//! vertices than the pool holds is not lost: the resolve pass drops that iteration whole, and
//! the host traces it again in smaller waves, drawing the same random numbers, so the film gets
//! exactly the iteration it would have had. Light subpaths are therefore never cut short and no
//! strategy ever leaves the MIS weights for want of storage.
//!
//! The merging methods (SPPM, VCM) merge with every light vertex of the iteration, so after a
//! wave's light subpaths they build the hash grid of its vertices in dispatches
//! (`shaders/hash_grid.wgsl`: setup, count, scan, scatter, sort) and run the camera pass over
//! the whole image: each pixel merges with the wave's photons, and takes emission, next-event
//! estimation and its connections in the wave that traced its own light subpath. Summed over
//! the waves, that is every strategy once, as in one wave (the merges are summed in another
//! order, so a multi-wave iteration equals the CPU's to f32 rounding, not bit for bit). An
//! iteration that overflows the pool is traced again after the pool has grown, up to what the
//! device binds; beyond that, in more waves: each costs a camera pass, but any iteration fits,
//! and N's bound keeps the waves of an iteration few at any image size.

use super::frame::{tally_words, CELL_WORDS, MAX_PASS_SPP};
use super::limits::{check_image_fits, largest_binding, splat_band_rows};
use super::pipeline::{buffer_entries, compute_pipeline, storage, Kernel};
use crate::accel::hash_grid::GridParams;
use crate::transport::merging::MergeRadius;
use crate::transport::method::Method;
use crate::transport::subpath::{LightVertex, PhotonRecord};
use anyhow::Result;
use wgpu::util::DeviceExt;

/// The word of an image cell that holds the light vertices a wave asked for (`CELL_VERTICES`).
pub(in crate::gpu) const CELL_VERTICES: usize = 6 + 1;
/// Light subpaths per workgroup of the light pass (`@workgroup_size(64)`).
pub(in crate::gpu) const LIGHT_WORKGROUP: u32 = 64;
/// Buckets per workgroup of the grid's prefix sum (`grid_scan_blocks` in
/// `shaders/hash_grid.wgsl`, which declares it again).
pub const SCAN_BLOCK: u32 = 1024;
/// Vertices per light subpath assumed before any is measured: a closed room with albedo 0.8
/// stores about 4, a white furnace of albedo 0.95 about 20.
pub(in crate::gpu) const FIRST_VERTICES_PER_PATH: f64 = 8.0;

/// The light-vertex pool and the hash grid over it, which grow together.
pub(in crate::gpu) struct Pool {
    pub(in crate::gpu) bind_group: wgpu::BindGroup,
    pub(in crate::gpu) vertices: wgpu::Buffer,
    pub(in crate::gpu) grid_params: wgpu::Buffer,
    pub(in crate::gpu) grid_entries: wgpu::Buffer,
    pub(in crate::gpu) grid_starts: wgpu::Buffer,
    pub(in crate::gpu) grid_cursor: wgpu::Buffer,
}

/// The merging methods' kernels and radius.
pub(in crate::gpu) struct Merging {
    pub(in crate::gpu) setup: wgpu::ComputePipeline,
    pub(in crate::gpu) count: wgpu::ComputePipeline,
    pub(in crate::gpu) scan_blocks: wgpu::ComputePipeline,
    pub(in crate::gpu) scan_sums: wgpu::ComputePipeline,
    pub(in crate::gpu) scan_add: wgpu::ComputePipeline,
    pub(in crate::gpu) scatter: wgpu::ComputePipeline,
    pub(in crate::gpu) sort: wgpu::ComputePipeline,
    pub(in crate::gpu) records: wgpu::ComputePipeline,
    /// The tests' search (`grid_query_check`).
    pub(in crate::gpu) query_check: wgpu::ComputePipeline,
    pub(in crate::gpu) radius: MergeRadius,
    /// The grid's origin (`merging::scene_bounds`), as on the CPU.
    pub(in crate::gpu) grid_min: glam::Vec3,
    /// The test-only fault `Faults::merge_kernel_ball`.
    pub(in crate::gpu) ball_kernel: bool,
}

/// Light tracing's, BDPT's, SPPM's and VCM's kernels and buffers.
pub struct Bidirectional {
    pub(in crate::gpu) light_pipeline: wgpu::ComputePipeline,
    /// All but light tracing.
    pub(in crate::gpu) camera_pipeline: Option<wgpu::ComputePipeline>,
    pub(in crate::gpu) resolve_pipeline: wgpu::ComputePipeline,
    pub(in crate::gpu) merging: Option<Merging>,
    pub(in crate::gpu) layout: wgpu::BindGroupLayout,
    pub(in crate::gpu) pool: Pool,
    pub(in crate::gpu) tallies: wgpu::Buffer,
    pub(in crate::gpu) camera_radiance: wgpu::Buffer,
    /// The most light vertices the device binds in one buffer.
    pub(in crate::gpu) max_capacity: u32,
    pub(in crate::gpu) tally_readback: wgpu::Buffer,
    /// Light vertices the pool holds.
    pub capacity: u32,
    /// Rows and pixels of a film band: the splat tallies, pass sums and camera radiance hold one
    /// band; an image larger than one binding is rendered band by band (`run_iterations`).
    pub(super) band_rows: u32,
    pub(super) band_pixels: u64,
    /// Each pixel's camera radiance lanes at the start of an iteration, (0, 0, 0, n_c), for
    /// images of several bands (the camera radiance buffer holds one band's).
    pub(in crate::gpu) n_c: Vec<[f32; 4]>,
    /// Light vertices per light subpath, as measured (with a margin), for sizing waves.
    pub(in crate::gpu) vertices_per_path: f64,
    /// Iterations traced again after a wave overflowed the pool.
    pub retraced: u64,
    /// The pixels whose centre ray meets a mirror or glass (`subpath::specular_pixels`).
    pub(in crate::gpu) specular: Vec<bool>,
    /// n_c in those pixels (`subpath::specular_camera_subpaths`).
    pub(in crate::gpu) specular_camera_subpaths: u32,
    /// N asked for (`--light-paths`, `MergeRadius::light_paths`; None: the default).
    pub(in crate::gpu) requested_light_paths: Option<u32>,
}

/// The camera radiance buffer's lanes at the start of an iteration, (0, 0, 0, n_c), per pixel.
pub(in crate::gpu) fn camera_radiance_lanes(camera_subpaths: &[u32]) -> Vec<[f32; 4]> {
    camera_subpaths
        .iter()
        .map(|&n| [0.0, 0.0, 0.0, n as f32])
        .collect()
}

impl Pool {
    /// The pool for `capacity` light vertices, and its grid: at most next_pow2(capacity)
    /// buckets, so bucket starts and cursors of that many + 1 words.
    pub(in crate::gpu) fn new(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        capacity: u32,
        tallies: &wgpu::Buffer,
        camera_radiance: &wgpu::Buffer,
    ) -> Pool {
        let vertices = storage(
            device,
            "light vertices",
            capacity as u64 * std::mem::size_of::<LightVertex>() as u64,
        );
        let grid_params = storage(
            device,
            "grid params",
            std::mem::size_of::<GridParams>() as u64,
        );
        let buckets = (capacity.max(1) as u64).next_power_of_two();
        let grid_starts = storage(device, "grid starts", 4 * (buckets + 1));
        let grid_cursor = storage(device, "grid cursor", 4 * (buckets + 1));
        let grid_entries = storage(device, "grid entries", 16 * capacity as u64);
        // What a merge reads of each entry's vertex (`PhotonRecord`), in entry order; the bind
        // group keeps it.
        let photon_records = storage(
            device,
            "photon records",
            capacity as u64 * std::mem::size_of::<PhotonRecord>() as u64,
        );
        let buffers = [
            &vertices,
            tallies,
            camera_radiance,
            &grid_params,
            &grid_starts,
            &grid_entries,
            &grid_cursor,
            &photon_records,
        ];
        let entries = buffer_entries(buffers.into_iter());
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("light subpaths"),
            layout,
            entries: &entries,
        });
        Pool {
            bind_group,
            vertices,
            grid_params,
            grid_entries,
            grid_starts,
            grid_cursor,
        }
    }
}

impl Bidirectional {
    pub(in crate::gpu) fn new(
        device: &wgpu::Device,
        kernel: Kernel<'_>,
        scene_layout: &wgpu::BindGroupLayout,
        method: Method,
        scene: &crate::layout::FlatScene,
        camera: &crate::transport::camera::Camera,
        ball_kernel: bool,
    ) -> Result<Bidirectional> {
        let (width, height) = (camera.width, camera.height);
        let pixels = width as u64 * height as u64;
        let limits = device.limits();
        let max_binding = largest_binding(&limits);
        let vertex_size = std::mem::size_of::<LightVertex>() as u64;
        // The splat tallies and per-pixel buffers in one binding each (the check `render` makes
        // before any work, so a direct caller gets the same sentence).
        check_image_fits(&limits, method, width, height).map_err(anyhow::Error::msg)?;
        let band_rows = splat_band_rows(max_binding, width, height).unwrap_or(1);
        let band_pixels = band_rows as u64 * width as u64;
        let tallies_size = 4 * tally_words(band_pixels);
        // The pool: room for the whole image at the first estimate, within what the device
        // binds (light tracing stores nothing). Grid entries are 16 bytes a vertex, photon
        // records 32, the vertices 80, so the vertices bound the pool.
        let max_capacity = (max_binding / vertex_size).min(u32::MAX as u64 / 2) as u32;
        let capacity = match method {
            Method::Light => 1,
            _ => ((pixels as f64 * FIRST_VERTICES_PER_PATH) as u64)
                .clamp(1 << 16, max_capacity as u64) as u32,
        };
        let tallies = storage(device, "tallies", tallies_size);
        // Each pixel's camera radiance of the iteration, and in the fourth lane its n_c
        // (`subpath::camera_subpaths`, 1 for light tracing), for the default radius until
        // `GpuRenderer::set_merge_radius` says otherwise.
        let specular = match method {
            Method::Light => vec![false; pixels as usize],
            _ => crate::transport::subpath::specular_pixels(scene, camera),
        };
        let default_radius = MergeRadius::default_for(scene, camera, method);
        let specular_camera_subpaths =
            crate::transport::subpath::specular_camera_subpaths(method, default_radius.initial);
        let n_c = camera_radiance_lanes(&crate::transport::subpath::camera_subpaths(
            &specular,
            specular_camera_subpaths,
        ));
        let camera_radiance = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("camera radiance"),
            contents: bytemuck::cast_slice(&n_c[..band_pixels as usize]),
            // Copies for the tests' grid check (`GpuRenderer::grid_check`).
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        });
        let tally_readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tally readback"),
            size: 4 * CELL_WORDS * MAX_PASS_SPP as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let entry = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("light subpaths"),
            entries: &(0..8).map(entry).collect::<Vec<_>>(),
        });
        let pool = Pool::new(device, &layout, capacity, &tallies, &camera_radiance);
        let layouts = [scene_layout, &layout];
        let pipeline = |entry| compute_pipeline(device, kernel, &layouts, entry);
        let merging = method.merges().then(|| Merging {
            setup: pipeline("grid_setup"),
            count: pipeline("grid_count"),
            scan_blocks: pipeline("grid_scan_blocks"),
            scan_sums: pipeline("grid_scan_sums"),
            scan_add: pipeline("grid_scan_add"),
            scatter: pipeline("grid_scatter"),
            sort: pipeline("grid_sort"),
            records: pipeline("grid_records"),
            query_check: pipeline("grid_query_check"),
            radius: default_radius,
            grid_min: crate::transport::merging::scene_bounds(scene).0,
            ball_kernel,
        });
        Ok(Bidirectional {
            light_pipeline: pipeline("light_pass"),
            // Photon mapping's camera pass gathers from the photon maps; the others' is BDPT's.
            camera_pipeline: (method != Method::Light).then(|| {
                pipeline(if method == Method::PhotonMap {
                    "photon_map_pass"
                } else {
                    "camera_pass"
                })
            }),
            resolve_pipeline: pipeline("resolve_pass"),
            merging,
            layout,
            pool,
            tallies,
            camera_radiance,
            max_capacity,
            tally_readback,
            capacity,
            band_rows,
            band_pixels,
            // For images of several bands (each uploads its own).
            n_c,
            vertices_per_path: FIRST_VERTICES_PER_PATH,
            retraced: 0,
            specular,
            specular_camera_subpaths,
            requested_light_paths: None,
        })
    }
}

impl Bidirectional {
    /// A new pool (and grid) for `capacity` light vertices, bound to the same tallies and
    /// camera radiance.
    pub(in crate::gpu) fn resize_pool(&mut self, device: &wgpu::Device, capacity: u32) {
        self.capacity = capacity;
        self.pool = Pool::new(
            device,
            &self.layout,
            capacity,
            &self.tallies,
            &self.camera_radiance,
        );
    }
}
