//! The GPU backend's work: upload the flattened scene as it is, compile the path-tracing
//! kernel, run it in bounded dispatches, and fold each pass's sums into the f64 film.

mod adaptive;
mod iterations;
mod radiosity;

use super::bidirectional::Bidirectional;
use super::frame::{
    Frame, PixelSums, MAX_PASS_SPP, STOP_LATENCY_SECONDS, TARGET_DISPATCH_SECONDS, WORKGROUP,
};
use super::limits::{
    array_lengths, check_scene_fits, largest_binding, PIXEL_RUN_BYTES, PIXEL_SUMS_BYTES,
};
use super::pipeline::{
    bind_group_layout, buffer_entries, compute_pipeline, packed_prims, upload, Kernel,
};
use super::radiosity::{radiosity_layout, Radiosity};
use super::shader::Residency;
use crate::film::Film;
use crate::layout::FlatScene;
use crate::transport::camera::Camera;
use crate::transport::faults::Faults;
use crate::transport::method::Method;
use anyhow::{anyhow, bail, Context, Result};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use wgpu::util::DeviceExt;

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
    /// The pass kernel of path tracing, whitted and radiosity (None for the light-subpath methods).
    pipeline: Option<wgpu::ComputePipeline>,
    pub(super) bind_group: wgpu::BindGroup,
    pub(super) frame_buffer: wgpu::Buffer,
    pub(super) sums: wgpu::Buffer,
    pub(super) readback: wgpu::Buffer,
    /// Adaptive sampling's pixel runs of a pass (`adaptive_pass_until`).
    pub(super) runs: wgpu::Buffer,
    /// The planted faults the host applies (`Faults::adaptive_pooled`).
    pub(super) faults: Faults,
    /// Image rows per film band: the pass sums of path tracing cover this many rows at a time,
    /// so that any image renders within the device's largest binding; the whole image for the
    /// other methods (`check_image_fits`).
    pub(super) film_rows: u32,
    pub(super) frame: Frame,
    pub(super) method: Method,
    /// The light-subpath methods: their kernels and buffers.
    pub(super) bidirectional: Option<Bidirectional>,
    /// Radiosity: its solve kernels and, once solved, its buffers (bind group 1 of its pass).
    pub(super) radiosity: Option<Radiosity>,
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

/// A flag and a message that wgpu's device-lost callback sets, for `check_device`.
fn watch_device_loss(device: &wgpu::Device) -> Arc<(AtomicBool, Mutex<String>)> {
    let lost = Arc::new((AtomicBool::new(false), Mutex::new(String::new())));
    let flag = lost.clone();
    device.set_device_lost_callback(move |reason, msg| {
        *flag.1.lock().unwrap() = format!("{reason:?}: {msg}");
        flag.0.store(true, Ordering::SeqCst);
    });
    lost
}

/// The kernel specialised to the scene (`shader::source`), with naga's runtime checks or
/// without them.
fn compile_kernel(
    device: &wgpu::Device,
    scene: &FlatScene,
    checks: Checks,
    residency: Residency,
) -> wgpu::ShaderModule {
    let source = super::shader::source(residency, array_lengths(scene));
    let desc = wgpu::ShaderModuleDescriptor {
        label: Some("hexray path tracer"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    };
    match checks {
        Checks::Checked => device.create_shader_module(desc),
        // SAFETY: the kernel's loops all terminate (BVH traversal visits each node at most
        // once; the path loop ends by Russian roulette with probability >= 0.05 per bounce
        // after bounce 3; the sample loop is counted), and every index is in bounds by
        // construction (node, primitive and material indices come from the flattened scene,
        // pixel indices are checked against the tile).
        Checks::Unchecked => unsafe {
            device.create_shader_module_trusted(desc, wgpu::ShaderRuntimeChecks::unchecked())
        },
    }
}

/// One film band's pass sums on the device, and the buffer they are read back through.
fn pixel_sums_buffers(
    device: &wgpu::Device,
    film_rows: u32,
    width: u32,
) -> (wgpu::Buffer, wgpu::Buffer) {
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
    (sums, readback)
}

/// Bind group 0 of `shaders/scene.wgsl`: the six scene arrays as `residency` lays them out, the
/// frame, the pass sums, the pixel runs.
fn scene_bind_group(
    device: &wgpu::Device,
    residency: Residency,
    scene: &FlatScene,
    layout: &wgpu::BindGroupLayout,
    frame_buffer: &wgpu::Buffer,
    (sums, runs): (&wgpu::Buffer, &wgpu::Buffer),
) -> Result<wgpu::BindGroup> {
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
    entries.push(wgpu::BindGroupEntry {
        binding: 8,
        resource: runs.as_entire_binding(),
    });
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("scene"),
        layout,
        entries: &entries,
    });
    if let Some(e) = pollster::block_on(scope.pop()) {
        bail!("binding the scene failed: {e}");
    }
    Ok(bind_group)
}

impl GpuRenderer {
    /// The traversal the scene's BVH is built for (`bvh::Traversal`): the shader tests a leaf's
    /// primitives one per loop turn.
    pub const TRAVERSAL: crate::accel::bvh::Traversal = crate::accel::bvh::Traversal::Shader;

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
        shadow_threshold: f32,
        pipeline_cache: Option<&wgpu::PipelineCache>,
    ) -> Result<GpuRenderer> {
        // A scene array beyond the binding limit would be a wgpu validation panic: say so first.
        check_scene_fits(&device.limits(), residency, scene).map_err(anyhow::Error::msg)?;
        let (width, height) = (camera.width, camera.height);
        let lost = watch_device_loss(device);

        // The kernel and its pipelines: path tracing's one, or the light-subpath methods' passes.
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = compile_kernel(device, scene, checks, residency);
        let kernel = Kernel {
            module: &module,
            cache: pipeline_cache,
        };
        let layout = bind_group_layout(device, residency);
        let mut radiosity = None;
        let (pipeline, bidirectional) = if method.splats() {
            let b = Bidirectional::new(
                device,
                kernel,
                &layout,
                method,
                scene,
                &camera,
                faults.merge_kernel_ball,
            )?;
            (None, Some(b))
        } else if method == Method::Radiosity {
            // The image pass reads the solution through bind group 2, as the solve kernels do.
            let r = Radiosity::new(
                device,
                kernel,
                &layout,
                radiosity_layout(device),
                scene,
                seed,
                faults,
            );
            let pipeline = compute_pipeline(
                device,
                kernel,
                &[&layout, &r.empty_layout, &r.layout],
                "radiosity_pass",
            );
            radiosity = Some(r);
            (Some(pipeline), None)
        } else {
            let entry = match method {
                Method::Whitted => "whitted_pass",
                _ => "render_pass",
            };
            (
                Some(compute_pipeline(device, kernel, &[&layout], entry)),
                None,
            )
        };
        if let Some(e) = pollster::block_on(scope.pop()) {
            bail!("the GPU rejected the {method} kernel: {e}");
        }

        let vertex_capacity = bidirectional.as_ref().map_or(0, |b| b.capacity);
        let frame = Frame::first(
            scene,
            camera,
            seed,
            faults,
            method,
            shadow_threshold,
            vertex_capacity,
        );
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
        let (sums, readback) = pixel_sums_buffers(device, film_rows, width);
        // Adaptive sampling's runs: at most one a pixel of a band (path tracing only).
        let run_slots = match method {
            Method::Path => film_rows as u64 * width as u64,
            _ => 1,
        };
        let runs = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pixel runs"),
            size: run_slots * PIXEL_RUN_BYTES,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let buffers = (&sums, &runs);
        let bind_group =
            scene_bind_group(device, residency, scene, &layout, &frame_buffer, buffers)?;
        Ok(GpuRenderer {
            device: device.clone(),
            queue: queue.clone(),
            pipeline,
            bind_group,
            frame_buffer,
            sums,
            readback,
            runs,
            faults,
            film_rows,
            frame,
            method,
            bidirectional,
            radiosity,
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
        self.render_until(first, count, film, &AtomicBool::new(false))
    }

    /// [`GpuRenderer::render`] until `stop` is set: the pass under way is dropped whole (its
    /// sums are not folded into the film), the passes before it stay. Where an iteration or a
    /// pass is long ([`GpuRenderer::stop_checked`]), the host waits for each dispatch before it
    /// queues the next and looks at `stop` between them, so that a stop takes effect within a
    /// dispatch's time (about `TARGET_DISPATCH_SECONDS`) at any image size.
    pub fn render_until(
        &mut self,
        first: u32,
        count: u32,
        film: &mut Film,
        stop: &AtomicBool,
    ) -> Result<()> {
        crate::film::check_film_for(self.method, film)?;
        // The film's samples are drawn with its sampler.
        self.frame.sampler = film.sampler.code();
        let mut done = 0;
        while done < count {
            let n = (count - done).min(MAX_PASS_SPP);
            let finished = if self.method.splats() {
                self.pass_bidirectional(first + done, n, film, stop)?
            } else {
                self.pass(first + done, n, film, stop)?
            };
            if !finished {
                break;
            }
            done += n;
        }
        Ok(())
    }

    /// Whether the queued work of a pass of `pixels` x `samples` paths should be waited for,
    /// dispatch by dispatch, to look at a stop between dispatches: where the pass would take
    /// longer than [`STOP_LATENCY_SECONDS`] at the throughput measured so far. Shorter passes
    /// run unwaited (the render loop looks at the stop between them).
    pub(super) fn stop_checked(&self, pixels: u64, samples: u32) -> bool {
        let paths_per_second = self.paths_per_dispatch as f64 / TARGET_DISPATCH_SECONDS;
        (pixels * samples as u64) as f64 / paths_per_second > STOP_LATENCY_SECONDS
    }

    /// Whether `stop` is set, after waiting for the work queued so far where `checked`
    /// ([`GpuRenderer::stop_checked`]); false at once where not.
    pub(super) fn stop_seen(&self, stop: &AtomicBool, checked: bool) -> bool {
        if !checked {
            return false;
        }
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
        stop.load(Ordering::SeqCst)
    }

    /// One pass of path tracing; false if `stop` cut it short (nothing folded).
    fn pass(&mut self, first: u32, count: u32, film: &mut Film, stop: &AtomicBool) -> Result<bool> {
        self.check_device()?;
        // Radiosity's solve, once, before its first pass.
        self.solve_radiosity()?;
        let (w, h) = (self.frame.camera.width, self.frame.camera.height);
        let start = Instant::now();
        let checked = self.stop_checked(w as u64 * h as u64, count);
        let finished = self.for_each_film_band(film, self.film_rows, |a, z| {
            // Only the first band may stop: later bands would leave rows of the pass folded.
            self.dispatch_band(first, count, a, z, stop, checked && a == 0)
        })?;
        if !finished {
            return Ok(false);
        }

        // Size the next dispatches from this pass's throughput.
        let image = (w as u64) * (h as u64);
        let paths_per_second = (image * count as u64) as f64 / start.elapsed().as_secs_f64();
        self.paths_per_dispatch =
            ((paths_per_second * TARGET_DISPATCH_SECONDS) as u64).clamp(4096, 1 << 28);
        Ok(true)
    }

    /// Film bands of `rows` rows (the whole image unless its per-pixel buffers are larger than
    /// one binding), in turn: clears the pass sums, queues `work(band_start, band_end)`, reads
    /// the band's sums back and folds them into the film in f64.
    pub(super) fn for_each_film_band(
        &self,
        film: &mut Film,
        rows: u32,
        work: impl FnMut(u32, u32) -> bool,
    ) -> Result<bool> {
        self.for_each_weighted_film_band(film, rows, |_| 1.0, work)
    }

    /// [`GpuRenderer::for_each_film_band`], each pixel's pass sums folded with `weight(pixel)`
    /// (adaptive sampling's weight of the pixel's run, `PixelStats::merge_weighted`).
    pub(super) fn for_each_weighted_film_band(
        &self,
        film: &mut Film,
        rows: u32,
        weight: impl Fn(usize) -> f64,
        mut work: impl FnMut(u32, u32) -> bool,
    ) -> Result<bool> {
        let h = self.frame.camera.height;
        let mut band_start = 0;
        while band_start < h {
            let band_end = (band_start + rows).min(h);
            let mut encoder = self.device.create_command_encoder(&Default::default());
            encoder.clear_buffer(&self.sums, 0, None);
            self.queue.submit([encoder.finish()]);
            if !work(band_start, band_end) {
                // Stopped (the first band alone may stop): nothing of the pass is folded.
                return Ok(false);
            }
            let mut encoder = self.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(&self.sums, 0, &self.readback, 0, None);
            self.queue.submit([encoder.finish()]);
            self.fold_sums(film, band_start, band_end - band_start, &weight)?;
            band_start = band_end;
        }
        Ok(true)
    }

    /// Queues samples `first..first + count` of rows `band_start..band_end` (one film band) in
    /// dispatches of about `paths_per_dispatch` paths, each of all `count` samples over as many
    /// rows as that allows (a multiple of the workgroup height, at least one workgroup): the
    /// lanes then have `count` samples each to regenerate their paths with (`render_pass` in
    /// `shaders/path.wgsl`). On lavapipe, 256x256, 64 spp, this gave 1.4 - 1.7x the camera
    /// paths/s of dispatches of one sample over more rows (docs/journal/2026-11-25_regeneration.md). The smallest dispatch,
    /// one workgroup of rows with 64 samples, can exceed the time target on a slow adapter
    /// (about 0.5 s at 256 pixels wide on lavapipe, which has no watchdog); a real GPU's budget
    /// holds many such dispatches.
    /// With `checked`, each dispatch is waited for and `stop` looked at before the next; returns
    /// false if it was set (the band's work is then incomplete).
    fn dispatch_band(
        &self,
        first: u32,
        count: u32,
        band_start: u32,
        band_end: u32,
        stop: &AtomicBool,
        checked: bool,
    ) -> bool {
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
            self.dispatch_pass(&frame);
            y += rows;
            if y < band_end && self.stop_seen(stop, checked) {
                return false;
            }
        }
        true
    }

    /// Submits one dispatch of the pass kernel over `frame`'s tile (workgroups of WORKGROUP x
    /// WORKGROUP), with `frame` as its uniform: one submission per dispatch, so that the
    /// uniform write lands before this dispatch and after the previous one.
    pub(super) fn dispatch_pass(&self, frame: &Frame) {
        self.queue
            .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(frame));
        let mut encoder = self.device.create_command_encoder(&Default::default());
        {
            let mut cpass = encoder.begin_compute_pass(&Default::default());
            cpass.set_pipeline(self.pipeline.as_ref().expect("the pass kernel"));
            cpass.set_bind_group(0, &self.bind_group, &[]);
            if let Some(r) = &self.radiosity {
                if let Some(solved) = &r.solved {
                    cpass.set_bind_group(1, &r.empty_group, &[]);
                    cpass.set_bind_group(2, &solved.bind_group, &[]);
                }
            }
            let [w, h] = frame.tile_size;
            cpass.dispatch_workgroups(w.div_ceil(WORKGROUP), h.div_ceil(WORKGROUP), 1);
        }
        self.queue.submit([encoder.finish()]);
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
    /// the film in f64, pixel p's with `weight(p)`: rows `first_row..first_row + rows`.
    fn fold_sums(
        &self,
        film: &mut Film,
        first_row: u32,
        rows: u32,
        weight: impl Fn(usize) -> f64,
    ) -> Result<()> {
        let bytes = self.read_buffer(&self.readback)?;
        let sums: Vec<PixelSums> = bytemuck::pod_collect_to_vec(&bytes);
        let w = film.width as usize;
        let start = first_row as usize * w;
        let band = &mut film.pixels[start..(first_row + rows) as usize * w];
        for (i, (p, s)) in band.iter_mut().zip(&sums).enumerate() {
            p.merge_weighted(&s.stats(), weight(start + i));
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
