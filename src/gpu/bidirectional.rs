//! The GPU's light tracing and BDPT: the host side of `shaders/light_path.wgsl`,
//! `shaders/bdpt.wgsl` and the resolve pass of `shaders/film.wgsl`.
//!
//! Each iteration is a sequence of dispatches over the same buffers, as on the CPU
//! (`cpu::render_iterations`): the light pass traces one light subpath per pixel, splatting its
//! connections to the camera into order-independent fixed-point tallies and (BDPT) storing its
//! diffuse vertices in a pool; the camera pass traces one camera subpath per pixel and connects
//! it to the light subpath of the same index; the resolve pass adds each pixel's camera radiance
//! and splats as one sample, and the image's sum for the iteration's batch mean.
//!
//! The pool holds the vertices of one *wave* of light subpaths (a band of rows of the image):
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
//! device binds; beyond that, in more waves: each costs a camera pass, but any iteration fits.

use super::render::{
    buffer_entries, compute_pipeline, Frame, GpuRenderer, MAX_PASS_SPP, WORKGROUP,
};
use crate::film::{Film, PixelStats};
use crate::hash_grid::GridParams;
use crate::merging::{kernel_normalization, MergeRadius};
use crate::method::Method;
use crate::subpath::{LightVertex, MergeMis};
use anyhow::{bail, Result};
use std::time::Instant;
use wgpu::util::DeviceExt;

/// Words of one tally cell (`CELL_WORDS` in `shaders/splat.wgsl`).
const CELL_WORDS: u64 = 8;
/// The word of an image cell that holds the light vertices a wave asked for (`CELL_VERTICES`).
const CELL_VERTICES: usize = 6 + 1;
/// Light subpaths per workgroup of the light pass (`@workgroup_size(64)`).
const LIGHT_WORKGROUP: u32 = 64;
/// Buckets per workgroup of the grid's prefix sum (`grid_scan_blocks` in
/// `shaders/hash_grid.wgsl`, which declares it again).
pub const SCAN_BLOCK: u32 = 1024;
/// Vertices per light subpath assumed before any is measured: a closed room with albedo 0.8
/// stores about 4, a white furnace of albedo 0.95 about 20.
const FIRST_VERTICES_PER_PATH: f64 = 8.0;

/// The light-vertex pool and the hash grid over it, which grow together.
struct Pool {
    bind_group: wgpu::BindGroup,
    vertices: wgpu::Buffer,
    grid_params: wgpu::Buffer,
    grid_entries: wgpu::Buffer,
    grid_starts: wgpu::Buffer,
    grid_cursor: wgpu::Buffer,
}

/// The merging methods' kernels and radius.
struct Merging {
    setup: wgpu::ComputePipeline,
    count: wgpu::ComputePipeline,
    scan_blocks: wgpu::ComputePipeline,
    scan_sums: wgpu::ComputePipeline,
    scan_add: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    sort: wgpu::ComputePipeline,
    /// The tests' search (`grid_query_check`).
    query_check: wgpu::ComputePipeline,
    radius: MergeRadius,
    /// The grid's origin (`merging::scene_bounds`), as on the CPU.
    grid_min: glam::Vec3,
    /// The test-only fault `Faults::merge_kernel_ball`.
    ball_kernel: bool,
}

/// Light tracing's, BDPT's, SPPM's and VCM's kernels and buffers.
pub struct Bidirectional {
    light_pipeline: wgpu::ComputePipeline,
    /// All but light tracing.
    camera_pipeline: Option<wgpu::ComputePipeline>,
    resolve_pipeline: wgpu::ComputePipeline,
    merging: Option<Merging>,
    layout: wgpu::BindGroupLayout,
    pool: Pool,
    tallies: wgpu::Buffer,
    camera_radiance: wgpu::Buffer,
    /// The most light vertices the device binds in one buffer.
    max_capacity: u32,
    tally_readback: wgpu::Buffer,
    /// Light vertices the pool holds.
    pub capacity: u32,
    /// Rows and pixels of a film band: the splat tallies, pass sums and camera radiance hold one
    /// band; an image larger than one binding is rendered band by band (`run_iterations`).
    pub(super) band_rows: u32,
    pub(super) band_pixels: u64,
    /// Each pixel's camera radiance lanes at the start of an iteration, (0, 0, 0, n_c), for
    /// images of several bands (the camera radiance buffer holds one band's).
    n_c: Vec<[f32; 4]>,
    /// Light vertices per light subpath, as measured (with a margin), for sizing waves.
    vertices_per_path: f64,
    /// Iterations traced again after a wave overflowed the pool.
    pub retraced: u64,
    /// The pixels whose centre ray meets a mirror or glass (`subpath::specular_pixels`).
    specular: Vec<bool>,
    /// n_c in those pixels (`subpath::specular_camera_subpaths`).
    specular_camera_subpaths: u32,
}

/// The camera radiance buffer's lanes at the start of an iteration, (0, 0, 0, n_c), per pixel.
fn camera_radiance_lanes(camera_subpaths: &[u32]) -> Vec<[f32; 4]> {
    camera_subpaths
        .iter()
        .map(|&n| [0.0, 0.0, 0.0, n as f32])
        .collect()
}

/// Word offsets into the tallies (`shaders/splat.wgsl`) for an image of `pixels` pixels.
fn image_cells_word(pixels: u64) -> u64 {
    pixels * CELL_WORDS
}
fn vertex_counter_word(pixels: u64) -> u64 {
    (pixels + MAX_PASS_SPP as u64) * CELL_WORDS
}
pub(crate) fn tally_words(pixels: u64) -> u64 {
    vertex_counter_word(pixels) + 1 + pixels
}

/// Rows per film band of the methods that splat: as many as keep the tallies (a splat cell and
/// a path head per pixel), the pass sums and the camera radiance of the band each within one
/// binding of `limit` bytes; the whole image if it fits, None if not even one row does.
pub(crate) fn splat_band_rows(limit: u64, width: u32, height: u32) -> Option<u32> {
    let fixed = 4 * tally_words(0);
    let per_pixel = (4 * (tally_words(1) - tally_words(0)))
        .max(std::mem::size_of::<super::render::PixelSums>() as u64)
        .max(16);
    let rows = limit.saturating_sub(fixed) / (per_pixel * width as u64);
    (rows > 0).then(|| rows.min(height as u64) as u32)
}

/// A storage buffer that copies can also read and write.
fn storage(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

impl Pool {
    /// The pool for `capacity` light vertices, and its grid: at most next_pow2(capacity)
    /// buckets, so bucket starts and cursors of that many + 1 words.
    fn new(
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
        let buffers = [
            &vertices,
            tallies,
            camera_radiance,
            &grid_params,
            &grid_starts,
            &grid_entries,
            &grid_cursor,
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
    pub fn new(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        scene_layout: &wgpu::BindGroupLayout,
        method: Method,
        scene: &crate::flat::FlatScene,
        camera: &crate::camera::Camera,
        ball_kernel: bool,
    ) -> Result<Bidirectional> {
        let (width, height) = (camera.width, camera.height);
        let pixels = width as u64 * height as u64;
        let limits = device.limits();
        let max_binding = super::render::largest_binding(&limits);
        let vertex_size = std::mem::size_of::<LightVertex>() as u64;
        // The splat tallies and per-pixel buffers in one binding each (the check `render` makes
        // before any work, so a direct caller gets the same sentence).
        super::render::check_image_fits(&limits, method, width, height)
            .map_err(anyhow::Error::msg)?;
        let band_rows = splat_band_rows(max_binding, width, height).unwrap_or(1);
        let band_pixels = band_rows as u64 * width as u64;
        let tallies_size = 4 * tally_words(band_pixels);
        // The pool: room for the whole image at the first estimate, within what the device
        // binds (light tracing stores nothing). Grid entries are 16 bytes a vertex, the
        // vertices 80, so the vertices bound the pool.
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
            _ => crate::subpath::specular_pixels(scene, camera),
        };
        let specular_camera_subpaths = crate::subpath::specular_camera_subpaths(
            method,
            MergeRadius::default_for(scene, method).initial,
        );
        let n_c = camera_radiance_lanes(&crate::subpath::camera_subpaths(
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
            entries: &(0..7).map(entry).collect::<Vec<_>>(),
        });
        let pool = Pool::new(device, &layout, capacity, &tallies, &camera_radiance);
        let layouts = [scene_layout, &layout];
        let pipeline = |entry| compute_pipeline(device, module, &layouts, entry);
        let merging = method.merges().then(|| Merging {
            setup: pipeline("grid_setup"),
            count: pipeline("grid_count"),
            scan_blocks: pipeline("grid_scan_blocks"),
            scan_sums: pipeline("grid_scan_sums"),
            scan_add: pipeline("grid_scan_add"),
            scatter: pipeline("grid_scatter"),
            sort: pipeline("grid_sort"),
            query_check: pipeline("grid_query_check"),
            radius: MergeRadius::default_for(scene, method),
            grid_min: crate::merging::scene_bounds(scene).0,
            ball_kernel,
        });
        Ok(Bidirectional {
            light_pipeline: pipeline("light_pass"),
            camera_pipeline: (method != Method::Light).then(|| pipeline("camera_pass")),
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
        })
    }
}

impl Bidirectional {
    /// A new pool (and grid) for `capacity` light vertices, bound to the same tallies and
    /// camera radiance.
    fn resize_pool(&mut self, device: &wgpu::Device, capacity: u32) {
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

impl GpuRenderer {
    /// Tests: at most `vertices` light vertices in the pool (as if the device bound no more),
    /// so that a small image needs several waves.
    pub fn set_max_light_vertices(&mut self, vertices: u32) {
        let b = self
            .bidirectional
            .as_mut()
            .expect("a method with light subpaths");
        b.max_capacity = vertices.max(1);
        if b.capacity > b.max_capacity {
            b.resize_pool(&self.device, b.max_capacity);
        }
        self.frame.vertex_capacity = b.capacity;
    }

    /// What the method chose or met (`Backend::provenance`): for BDPT its τ and n_c, and the
    /// iterations traced again after a wave overflowed the light-vertex pool.
    pub fn provenance(&self) -> Vec<(&'static str, String)> {
        match &self.bidirectional {
            Some(b) if b.camera_pipeline.is_some() => {
                let mut v = if self.method.connects() {
                    crate::render::bidirectional_provenance(
                        self.frame.shadow_threshold,
                        b.specular_camera_subpaths,
                        b.specular.iter().filter(|&&s| s).count(),
                    )
                } else {
                    Vec::new()
                };
                if let Some(m) = &b.merging {
                    v.extend(crate::render::merging_provenance(&m.radius));
                }
                v.push((
                    "light_vertex_pool",
                    format!(
                        "{} vertices, {} iterations traced again",
                        b.capacity, b.retraced
                    ),
                ));
                v
            }
            _ => Vec::new(),
        }
    }

    /// One pass of light tracing or BDPT: iterations `first..first + count` (at most
    /// MAX_PASS_SPP), and again those whose waves overflowed the vertex pool, until every one
    /// has landed in the film.
    pub(super) fn pass_bidirectional(
        &mut self,
        first: u32,
        count: u32,
        film: &mut Film,
    ) -> Result<()> {
        let mut pending: Vec<u32> = (first..first + count).collect();
        while !pending.is_empty() {
            pending = self.run_iterations(&pending, film)?;
        }
        Ok(())
    }

    /// With the `stage-times` feature, waits for the GPU and charges the time since the last
    /// mark to `stage` (`stage_times.rs`); nothing otherwise.
    #[inline(always)]
    fn mark(&self, _stage: &'static str) {
        #[cfg(feature = "stage-times")]
        self.stage_times.mark(&self.device, _stage);
    }

    /// Writes `frame` to the uniform and runs one dispatch of `pipeline` with it.
    fn dispatch(&self, pipeline: &wgpu::ComputePipeline, frame: &Frame, groups: (u32, u32)) {
        let b = self.bidirectional.as_ref().expect("light subpath buffers");
        self.queue
            .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(frame));
        let mut encoder = self.device.create_command_encoder(&Default::default());
        {
            let mut cpass = encoder.begin_compute_pass(&Default::default());
            cpass.set_pipeline(pipeline);
            cpass.set_bind_group(0, &self.bind_group, &[]);
            cpass.set_bind_group(1, &b.pool.bind_group, &[]);
            cpass.dispatch_workgroups(groups.0, groups.1, 1);
        }
        self.queue.submit([encoder.finish()]);
    }

    /// The merge radius's schedule of SPPM and VCM (`--radius`, `--alpha`), and with it n_c
    /// (`subpath::specular_camera_subpaths`: VCM with the radius 0 is BDPT).
    pub fn set_merge_radius(&mut self, radius: MergeRadius) {
        let method = self.method;
        let Some(b) = self.bidirectional.as_mut() else {
            return;
        };
        if let Some(m) = b.merging.as_mut() {
            m.radius = radius;
        }
        if method != Method::Light {
            let count = crate::subpath::specular_camera_subpaths(method, radius.initial);
            b.specular_camera_subpaths = count;
            b.n_c = camera_radiance_lanes(&crate::subpath::camera_subpaths(&b.specular, count));
            let band = b.band_pixels as usize;
            self.queue
                .write_buffer(&b.camera_radiance, 0, bytemuck::cast_slice(&b.n_c[..band]));
        }
    }

    /// Runs `pipeline` once per item `0..count` (`frame.path_origin` + the invocation), in
    /// workgroups of 64.
    fn item_dispatches(&self, pipeline: &wgpu::ComputePipeline, frame: &Frame, count: u32) {
        self.dispatches(pipeline, frame, 0, count, LIGHT_WORKGROUP);
    }

    /// Runs `pipeline` once per workgroup-sized block `first..end` (`frame.path_origin` + the
    /// workgroup).
    fn block_dispatches(
        &self,
        pipeline: &wgpu::ComputePipeline,
        frame: &Frame,
        first: u32,
        end: u32,
    ) {
        self.dispatches(pipeline, frame, first, end, 1);
    }

    /// Items `first..end`, `per_group` to a workgroup, in dispatches of at most 65535 workgroups,
    /// each told its first item in `frame.path_origin`.
    fn dispatches(
        &self,
        pipeline: &wgpu::ComputePipeline,
        frame: &Frame,
        first: u32,
        end: u32,
        per_group: u32,
    ) {
        let per = 65_535 * per_group;
        let mut a = first;
        while a < end {
            let n = per.min(end - a);
            let f = Frame {
                path_origin: a,
                ..*frame
            };
            self.dispatch(pipeline, &f, (n.div_ceil(per_group), 1));
            a += n;
        }
    }

    /// Builds the hash grid over the pool's light vertices (`shaders/hash_grid.wgsl`), for the
    /// iteration whose frame (with its merge constants) is `frame`, merging within `radius`.
    fn build_grid(&self, frame: &Frame, radius: f32) {
        let b = self.bidirectional.as_ref().expect("light subpath buffers");
        let m = b.merging.as_ref().expect("a merging method");
        let params = GridParams::new(m.grid_min, 0, radius);
        self.queue
            .write_buffer(&b.pool.grid_params, 0, bytemuck::bytes_of(&params));
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&b.pool.grid_starts, 0, None);
        self.queue.submit([encoder.finish()]);
        let buckets = (b.capacity.max(1) as u64).next_power_of_two() as u32;
        self.dispatch(&m.setup, frame, (1, 1));
        self.item_dispatches(&m.count, frame, b.capacity);
        self.mark("grid count");
        // The prefix sum in blocks of SCAN_BLOCK (`hash_grid.wgsl`), dispatched for the largest
        // bucket count; blocks past this iteration's count scan zeros and store nothing.
        let blocks = buckets.div_ceil(SCAN_BLOCK);
        self.block_dispatches(&m.scan_blocks, frame, 0, blocks);
        self.dispatch(&m.scan_sums, frame, (1, 1));
        self.block_dispatches(&m.scan_add, frame, 1, blocks);
        self.mark("grid scan");
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&b.pool.grid_starts, 0, &b.pool.grid_cursor, 0, None);
        self.queue.submit([encoder.finish()]);
        self.item_dispatches(&m.scatter, frame, b.capacity);
        self.mark("grid scatter");
        self.item_dispatches(&m.sort, frame, buckets);
        self.mark("grid sort");
    }

    /// For tests: the hash grid the GPU builds over `points` (stored as the light vertices of
    /// subpaths 0.., one each) with cells for `radius`, read back, and for each query point
    /// what merging's search finds (`grid_query_check`): (count, sum of indices mod 2^20, xor
    /// of hashed indices >> 9). Needs a merging method, at most the pool's capacity of points
    /// and at most the image's pixels of queries.
    pub fn grid_check(
        &mut self,
        points: &[glam::Vec3],
        queries: &[glam::Vec3],
        radius: f32,
    ) -> Result<(crate::hash_grid::HashGrid, Vec<[u32; 3]>)> {
        let b = self.bidirectional.as_ref().expect("light subpath buffers");
        let pixels = b.band_pixels;
        let Some(m) = b.merging.as_ref() else {
            bail!("the grid check needs a merging method");
        };
        if points.len() > b.capacity as usize || queries.len() as u64 > pixels {
            bail!("too many points or queries for the pool and the image");
        }
        let vertices: Vec<LightVertex> = points
            .iter()
            .enumerate()
            .map(|(i, p)| LightVertex {
                p: p.to_array(),
                length: 1,
                path: i as u32,
                ..Default::default()
            })
            .collect();
        let q: Vec<[f32; 4]> = queries.iter().map(|p| p.extend(0.0).to_array()).collect();
        self.queue
            .write_buffer(&b.pool.vertices, 0, bytemuck::cast_slice(&vertices));
        self.queue.write_buffer(
            &b.tallies,
            4 * vertex_counter_word(pixels),
            bytemuck::bytes_of(&(points.len() as u32)),
        );
        self.queue
            .write_buffer(&b.camera_radiance, 0, bytemuck::cast_slice(&q));
        let frame = Frame {
            vertex_capacity: b.capacity,
            path_count: queries.len() as u32,
            ..self.frame
        };
        self.build_grid(&frame, radius);
        self.item_dispatches(&m.query_check, &frame, queries.len() as u32);
        // Storage buffers are not mappable: copy the first `size` bytes out through a staging
        // buffer.
        let read = |buffer: &wgpu::Buffer, size: u64| -> Result<Vec<u8>> {
            let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("grid check readback"),
                size: size.max(16),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut encoder = self.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, Some(size));
            self.queue.submit([encoder.finish()]);
            let mut bytes = self.read_buffer(&staging)?;
            bytes.truncate(size as usize);
            Ok(bytes)
        };
        let params: crate::hash_grid::GridParams = bytemuck::pod_read_unaligned(&read(
            &b.pool.grid_params,
            std::mem::size_of::<crate::hash_grid::GridParams>() as u64,
        )?);
        let starts: Vec<u32> = bytemuck::cast_slice(&read(
            &b.pool.grid_starts,
            4 * (params.buckets() as u64 + 1),
        )?)
        .to_vec();
        let entries: Vec<[f32; 4]> =
            bytemuck::cast_slice(&read(&b.pool.grid_entries, 16 * points.len() as u64)?).to_vec();
        let found: Vec<[u32; 3]> = bytemuck::cast_slice::<u8, [f32; 4]>(&read(
            &b.camera_radiance,
            16 * queries.len() as u64,
        )?)
        .iter()
        .map(|v| [v[0] as u32, v[1] as u32, v[2] as u32])
        .collect();
        let grid = crate::hash_grid::HashGrid {
            params,
            starts,
            entries,
        };
        Ok((grid, found))
    }

    /// Runs the light pass over subpaths `origin..origin + count`, in dispatches of about
    /// `paths_per_dispatch`.
    fn light_dispatches(&self, frame: &Frame, origin: u32, count: u32) {
        let b = self.bidirectional.as_ref().expect("light subpath buffers");
        let per = (self
            .paths_per_dispatch
            .clamp(LIGHT_WORKGROUP as u64, 65_535 * LIGHT_WORKGROUP as u64)
            as u32)
            / LIGHT_WORKGROUP
            * LIGHT_WORKGROUP;
        let mut a = 0;
        while a < count {
            let n = per.min(count - a);
            let f = Frame {
                path_origin: origin + a,
                path_count: n,
                ..*frame
            };
            self.dispatch(&b.light_pipeline, &f, (n.div_ceil(LIGHT_WORKGROUP), 1));
            a += n;
        }
    }

    /// Runs `pipeline` over rows `y0..y1`, in bands of about `paths_per_dispatch` pixels.
    fn row_dispatches(&self, pipeline: &wgpu::ComputePipeline, frame: &Frame, y0: u32, y1: u32) {
        let w = frame.camera.width;
        let rows =
            ((self.paths_per_dispatch / w as u64).max(1) as u32).div_ceil(WORKGROUP) * WORKGROUP;
        let mut y = y0;
        while y < y1 {
            let band = rows.min(y1 - y);
            let f = Frame {
                tile_origin: [0, y],
                tile_size: [w, band],
                ..*frame
            };
            self.dispatch(
                pipeline,
                &f,
                (w.div_ceil(WORKGROUP), band.div_ceil(WORKGROUP)),
            );
            y += band;
        }
    }

    /// Traces the given iterations (one slot each) and folds those that landed into the film;
    /// returns those that a wave overflowed, after enlarging what needs to be enlarged.
    fn run_iterations(&mut self, iterations: &[u32], film: &mut Film) -> Result<Vec<u32>> {
        self.check_device()?;
        let start = Instant::now();
        let (w, h) = (self.frame.camera.width, self.frame.camera.height);
        let pixels = w as u64 * h as u64;
        let b = self.bidirectional.as_ref().expect("light subpath buffers");
        let band_pixels = b.band_pixels;
        // Rows per wave: as many as the pool holds at the measured vertices per subpath, and at
        // most a band's (the pool's path heads are a band's). A merging iteration needs every
        // light vertex of the iteration, so each of its waves is followed by a camera pass over
        // the whole band (merges with that wave's photons; the other strategies in the pixel's
        // own wave); one wave when the pool holds them all. Light tracing stores nothing.
        let merging = b.merging.as_ref().is_some_and(|m| m.radius.initial > 0.0);
        let wave_rows = if b.camera_pipeline.is_none() {
            b.band_rows
        } else {
            ((b.capacity as f64 / (b.vertices_per_path * w as f64)) as u32).clamp(1, b.band_rows)
        };

        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(
            &b.tallies,
            4 * image_cells_word(band_pixels),
            Some(4 * CELL_WORDS * MAX_PASS_SPP as u64),
        );
        self.queue.submit([encoder.finish()]);
        #[cfg(feature = "stage-times")]
        self.stage_times.start();
        // Film bands: the image, unless its tallies are larger than one binding. Every band
        // traces every light subpath of the iteration (splatting only into the band), so each
        // band's pixels get the whole estimate, and the iteration's image sum gathers all bands.
        self.for_each_film_band(film, b.band_rows, |band_start, band_end| {
            if b.band_rows < h {
                let a = (band_start * w) as usize;
                let z = (band_end * w) as usize;
                self.queue
                    .write_buffer(&b.camera_radiance, 0, bytemuck::cast_slice(&b.n_c[a..z]));
            }
            for (slot, &s) in iterations.iter().enumerate() {
                // Merging's radius this iteration, its constants in the MIS weights and the
                // kernel's normalisation, as on the CPU (`cpu::render_iterations`).
                let radius = b.merging.as_ref().map_or(0.0, |m| m.radius.at(s));
                let merge = MergeMis::new(radius, pixels as u32, self.method);
                let ball = b.merging.as_ref().is_some_and(|m| m.ball_kernel);
                let normalization = kernel_normalization(radius, pixels as u32, ball);
                let frame = Frame {
                    first_sample: s,
                    sample_count: 1,
                    slot: slot as u32,
                    vertex_capacity: b.capacity,
                    merge_vm: merge.vm,
                    merge_vc: merge.vc,
                    camera_goes_on: merge.camera_goes_on as u32,
                    merge_normalization: normalization,
                    merge_radius: radius,
                    merges_within_clearance: self.frame.merges_within_clearance
                        & (radius > 0.0) as u32,
                    film_row: band_start,
                    film_rows: band_end - band_start,
                    band_pixels: band_pixels as u32,
                    ..self.frame
                };
                // Wave by wave: the light subpaths of a band of rows (with the pool's counter
                // cleared before each), then the camera subpaths: BDPT's of the wave's pixels in
                // the film band, a merging method's of the whole film band.
                let mut y = 0;
                while y < h {
                    let y1 = (y + wave_rows).min(h);
                    let wave = Frame {
                        path_origin: y * w,
                        path_count: (y1 - y) * w,
                        wave_origin: y * w,
                        ..frame
                    };
                    let mut encoder = self.device.create_command_encoder(&Default::default());
                    encoder.clear_buffer(&b.tallies, 4 * vertex_counter_word(band_pixels), Some(4));
                    self.queue.submit([encoder.finish()]);
                    self.light_dispatches(&wave, y * w, (y1 - y) * w);
                    self.mark("light");
                    if let Some(camera) = &b.camera_pipeline {
                        if merging {
                            self.build_grid(&wave, radius);
                            self.row_dispatches(camera, &wave, band_start, band_end);
                        } else if y.max(band_start) < y1.min(band_end) {
                            self.row_dispatches(camera, &wave, y.max(band_start), y1.min(band_end));
                        }
                        self.mark("camera");
                    }
                    y = y1;
                }
                self.row_dispatches(&b.resolve_pipeline, &frame, band_start, band_end);
                self.mark("resolve");
            }
        })?;

        // Read back the iterations' image cells.
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(
            &b.tallies,
            4 * image_cells_word(band_pixels),
            &b.tally_readback,
            0,
            Some(4 * CELL_WORDS * MAX_PASS_SPP as u64),
        );
        self.queue.submit([encoder.finish()]);
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&self.read_buffer(&b.tally_readback)?);
        self.mark("readback");

        let mut overflowed = Vec::new();
        let mut most_asked = 0u32;
        for (slot, &s) in iterations.iter().enumerate() {
            let cell = &words[slot * CELL_WORDS as usize..(slot + 1) * CELL_WORDS as usize];
            most_asked = most_asked.max(cell[CELL_VERTICES]);
            if cell[CELL_VERTICES] > b.capacity {
                overflowed.push(s);
                continue;
            }
            // The iteration's image mean, one sample of the image mean's batch statistics;
            // an overflowed sum is dropped like a non-finite sample.
            let mean = if cell[6] != 0 {
                glam::Vec3::NAN
            } else {
                let sum = |c: usize| {
                    crate::splat::from_fixed(cell[2 * c] as u64 | (cell[2 * c + 1] as u64) << 32)
                };
                glam::Vec3::new(sum(0) as f32, sum(1) as f32, sum(2) as f32) / pixels as f32
            };
            film.iteration_means
                .get_or_insert_with(PixelStats::default)
                .add(mean);
        }

        // Size the next waves and dispatches from what this pass measured.
        let b = self.bidirectional.as_mut().expect("light subpath buffers");
        if !overflowed.is_empty() {
            b.retraced += overflowed.len() as u64;
        }
        if b.camera_pipeline.is_some() {
            let asked_per_path = most_asked as f64 / (wave_rows as f64 * w as f64);
            b.vertices_per_path = (1.25 * asked_per_path).max(0.5);
        }
        if merging && !overflowed.is_empty() && b.capacity < b.max_capacity {
            // One wave is cheapest (every further wave is a camera pass over the whole image):
            // grow the pool and its grid first, up to what the device binds.
            let capacity = ((most_asked as u64 * 5 / 4).max(2 * b.capacity as u64))
                .min(b.max_capacity as u64) as u32;
            b.resize_pool(&self.device, capacity);
        } else if !overflowed.is_empty() && wave_rows == 1 {
            bail!(
                "{}: one row of {w} light subpaths stored {most_asked} vertices, more than the \
                 GPU's vertex pool holds ({}); render a narrower image, or use --backend cpu",
                self.method,
                b.capacity
            );
        }
        let landed = (iterations.len() - overflowed.len()) as u64;
        if landed > 0 {
            let paths_per_second = (pixels * landed) as f64 / start.elapsed().as_secs_f64();
            self.paths_per_dispatch = ((paths_per_second * super::render::TARGET_DISPATCH_SECONDS)
                as u64)
                .clamp(4096, 1 << 28);
        }
        Ok(overflowed)
    }
}
