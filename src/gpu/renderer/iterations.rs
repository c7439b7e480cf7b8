//! The iterations of the light-subpath methods (light tracing, BDPT, SPPM, VCM) on the GPU, as
//! [`GpuRenderer`]'s passes: each iteration a light pass, for the merging methods the hash grid
//! over its vertices, a camera pass and a resolve pass over the buffers of
//! [`Bidirectional`](crate::gpu::bidirectional::Bidirectional), wave by wave, as on the CPU
//! (`cpu::render_iterations`).

use super::GpuRenderer;
use crate::accel::hash_grid::GridParams;
use crate::film::{Film, PixelStats};
use crate::gpu::bidirectional::{
    camera_radiance_lanes, CELL_VERTICES, LIGHT_WORKGROUP, SCAN_BLOCK,
};
use crate::gpu::frame::{image_cells_word, vertex_counter_word, CELL_WORDS, WORKGROUP};
use crate::gpu::frame::{Frame, MAX_PASS_SPP, TARGET_DISPATCH_SECONDS};
use crate::transport::merging::{self, kernel_normalization, MergeRadius};
use crate::transport::method::Method;
use crate::transport::subpath::LightVertex;
use crate::transport::subpath::MergeMis;
use anyhow::{bail, Result};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

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

    /// N, the light subpaths of an iteration (`merging::light_paths`), as on the CPU.
    fn light_paths(&self) -> u32 {
        let (w, h) = (self.frame.camera.width, self.frame.camera.height);
        let pixels = w as u64 * h as u64;
        let b = self.bidirectional.as_ref().expect("light subpath buffers");
        match &b.merging {
            Some(m) => m.radius.light_paths_for(self.method, pixels),
            None => merging::light_paths(self.method, pixels, b.requested_light_paths),
        }
    }

    /// What the method chose or met (`Backend::provenance`): for BDPT its τ and n_c, and the
    /// iterations traced again after a wave overflowed the light-vertex pool; for radiosity its
    /// patches and solve.
    pub fn provenance(&self) -> Vec<(&'static str, String)> {
        let Some(b) = &self.bidirectional else {
            return self.radiosity_provenance();
        };
        let mut v = if self.method.connects() {
            crate::film::provenance::bidirectional_provenance(
                self.frame.shadow_threshold,
                b.specular_camera_subpaths,
                b.specular.iter().filter(|&&s| s).count(),
            )
        } else {
            Vec::new()
        };
        v.push(("light_paths", self.light_paths().to_string()));
        if let Some(m) = &b.merging {
            v.extend(crate::film::provenance::merging_provenance(&m.radius));
        }
        if b.camera_pipeline.is_some() {
            v.push((
                "light_vertex_pool",
                format!(
                    "{} vertices, {} iterations traced again",
                    b.capacity, b.retraced
                ),
            ));
        }
        v
    }

    /// One pass of a light-subpath method: iterations `first..first + count` (at most
    /// MAX_PASS_SPP), and again those whose waves overflowed the vertex pool, until every one
    /// has landed in the film; false if `stop` cut it short (the run under way is not folded).
    pub(super) fn pass_bidirectional(
        &mut self,
        first: u32,
        count: u32,
        film: &mut Film,
        stop: &AtomicBool,
    ) -> Result<bool> {
        let mut pending: Vec<u32> = (first..first + count).collect();
        while !pending.is_empty() {
            match self.run_iterations(&pending, film, stop)? {
                Some(overflowed) => pending = overflowed,
                None => return Ok(false),
            }
        }
        Ok(true)
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
        b.requested_light_paths = radius.light_paths;
        if method != Method::Light {
            let count = crate::transport::subpath::specular_camera_subpaths(method, radius.initial);
            b.specular_camera_subpaths = count;
            b.n_c = camera_radiance_lanes(&crate::transport::subpath::camera_subpaths(
                &b.specular,
                count,
            ));
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
        self.item_dispatches(&m.records, frame, b.capacity);
        self.mark("grid records");
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
    ) -> Result<(crate::accel::hash_grid::HashGrid, Vec<[u32; 3]>)> {
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
        let params: crate::accel::hash_grid::GridParams = bytemuck::pod_read_unaligned(&read(
            &b.pool.grid_params,
            std::mem::size_of::<crate::accel::hash_grid::GridParams>() as u64,
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
        let grid = crate::accel::hash_grid::HashGrid {
            params,
            starts,
            entries,
        };
        Ok((grid, found))
    }

    /// Runs the light pass over subpaths `origin..origin + count`, in dispatches of about
    /// `paths_per_dispatch`; with `checked`, each waited for and `stop` looked at before the
    /// next (false if it was set).
    fn light_dispatches(
        &self,
        frame: &Frame,
        origin: u32,
        count: u32,
        stop: &AtomicBool,
        checked: bool,
    ) -> bool {
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
            if self.stop_seen(stop, checked) {
                return false;
            }
        }
        true
    }

    /// Runs `pipeline` over rows `y0..y1`, in bands of about `paths_per_dispatch` pixels; with
    /// `checked`, each waited for and `stop` looked at before the next (false if it was set).
    #[allow(clippy::too_many_arguments)]
    fn row_dispatches(
        &self,
        pipeline: &wgpu::ComputePipeline,
        frame: &Frame,
        y0: u32,
        y1: u32,
        stop: &AtomicBool,
        checked: bool,
    ) -> bool {
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
            if self.stop_seen(stop, checked) {
                return false;
            }
        }
        true
    }

    /// Traces the given iterations (one slot each) and folds those that landed into the film;
    /// returns those that a wave overflowed, after enlarging what needs to be enlarged, or None
    /// where `stop` cut the run short (nothing of it folded).
    fn run_iterations(
        &mut self,
        iterations: &[u32],
        film: &mut Film,
        stop: &AtomicBool,
    ) -> Result<Option<Vec<u32>>> {
        self.check_device()?;
        let start = Instant::now();
        let (w, h) = (self.frame.camera.width, self.frame.camera.height);
        let pixels = w as u64 * h as u64;
        let n_paths = self.light_paths();
        let b = self.bidirectional.as_ref().expect("light subpath buffers");
        let band_pixels = b.band_pixels;
        // Light subpaths per wave: as many as the pool holds at the measured vertices per
        // subpath, and at most a band's pixels (the pool's path heads are a band's); whole rows
        // of the image for BDPT, whose camera pass covers the wave's own pixels. A merging
        // iteration needs every light vertex of the iteration, so each of its waves is followed
        // by a camera pass over the whole band (merges with that wave's photons; the other
        // strategies where the pixel's light subpath, index mod N, is the wave's); one wave when
        // the pool holds them all, which N bounds. Light tracing stores nothing.
        let merging = b.merging.as_ref().is_some_and(|m| m.radius.initial > 0.0);
        let wave_paths = if b.camera_pipeline.is_none() {
            b.band_rows * w
        } else {
            let rows = ((b.capacity as f64 / (b.vertices_per_path * w as f64)) as u32)
                .clamp(1, b.band_rows);
            rows * w
        };

        // An iteration costs about three path-traced samples (light, camera and connections).
        let checked = self.stop_checked(pixels, 3 * iterations.len() as u32);
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
        let finished = self.for_each_film_band(film, b.band_rows, |band_start, band_end| {
            // Only the first band may stop: later bands would leave rows of the run folded.
            let checked = checked && band_start == 0;
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
                let merge = MergeMis::new(radius, n_paths, self.method);
                let ball = b.merging.as_ref().is_some_and(|m| m.ball_kernel);
                let normalization = kernel_normalization(radius, n_paths, ball);
                let frame = Frame {
                    n_light_paths: n_paths,
                    first_sample: s,
                    sample_count: 1,
                    slot: slot as u32,
                    vertex_capacity: b.capacity,
                    merge_vm: merge.vm,
                    merge_vc: merge.vc,
                    camera_goes_on: merge.camera_goes_on as u32,
                    merge_normalization: normalization,
                    merge_radius: radius,
                    merge_reach: b.merging.as_ref().map_or(0.0, |m| m.radius.reach),
                    merges_within_clearance: self.frame.merges_within_clearance
                        & (radius > 0.0) as u32,
                    film_row: band_start,
                    film_rows: band_end - band_start,
                    band_pixels: band_pixels as u32,
                    ..self.frame
                };
                // Wave by wave: light subpaths p0..p1 (with the pool's counter cleared before
                // each), then the camera subpaths in the film band: BDPT's of the pixels whose
                // light subpath is the wave's (`own_rows`), a merging method's of every pixel.
                let mut p0 = 0;
                while p0 < n_paths {
                    let p1 = (p0 + wave_paths).min(n_paths);
                    let wave = Frame {
                        path_origin: p0,
                        path_count: p1 - p0,
                        wave_origin: p0,
                        ..frame
                    };
                    let mut encoder = self.device.create_command_encoder(&Default::default());
                    encoder.clear_buffer(&b.tallies, 4 * vertex_counter_word(band_pixels), Some(4));
                    self.queue.submit([encoder.finish()]);
                    if !self.light_dispatches(&wave, p0, p1 - p0, stop, checked) {
                        return false;
                    }
                    self.mark("light");
                    if let Some(camera) = &b.camera_pipeline {
                        let (a, z) = if merging {
                            self.build_grid(&wave, radius);
                            (band_start, band_end)
                        } else {
                            own_rows(p0, p1, n_paths, w, h)
                        };
                        let (a, z) = (a.max(band_start), z.min(band_end));
                        if a < z && !self.row_dispatches(camera, &wave, a, z, stop, checked) {
                            return false;
                        }
                        self.mark("camera");
                    }
                    p0 = p1;
                }
                let never = AtomicBool::new(false);
                self.row_dispatches(
                    &b.resolve_pipeline,
                    &frame,
                    band_start,
                    band_end,
                    &never,
                    false,
                );
                self.mark("resolve");
            }
            true
        })?;
        if !finished {
            // The dropped iteration's splats are not resolved, so they are cleared here: the
            // next iteration starts from empty cells, as after a resolve.
            let b = self.bidirectional.as_ref().expect("light subpath buffers");
            let mut encoder = self.device.create_command_encoder(&Default::default());
            encoder.clear_buffer(&b.tallies, 0, Some(4 * image_cells_word(band_pixels)));
            self.queue.submit([encoder.finish()]);
            return Ok(None);
        }

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
                    crate::transport::splat::from_fixed(
                        cell[2 * c] as u64 | (cell[2 * c + 1] as u64) << 32,
                    )
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
            let asked_per_path = most_asked as f64 / wave_paths.min(n_paths) as f64;
            b.vertices_per_path = (1.25 * asked_per_path).max(0.5);
        }
        if merging && !overflowed.is_empty() && b.capacity < b.max_capacity {
            // One wave is cheapest (every further wave is a camera pass over the whole image):
            // grow the pool and its grid first, up to what the device binds.
            let capacity = ((most_asked as u64 * 5 / 4).max(2 * b.capacity as u64))
                .min(b.max_capacity as u64) as u32;
            b.resize_pool(&self.device, capacity);
        } else if !overflowed.is_empty() && wave_paths == w {
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
            self.paths_per_dispatch =
                ((paths_per_second * TARGET_DISPATCH_SECONDS) as u64).clamp(4096, 1 << 28);
        }
        Ok(Some(overflowed))
    }
}

/// The rows that hold the pixels whose light subpath (pixel index mod `n_paths`) is one of
/// `p0..p1`, on an image `w` x `h`: the wave's own rows where N is the pixels, all rows where
/// the pixels share light subpaths (their camera pass skips the pixels the wave does not own).
fn own_rows(p0: u32, p1: u32, n_paths: u32, w: u32, h: u32) -> (u32, u32) {
    if (n_paths as u64) < w as u64 * h as u64 {
        (0, h)
    } else {
        (p0 / w, p1.div_ceil(w))
    }
}
