//! The benchmark: each scene on each backend at a fixed sample count, timed apart from its
//! warm-up. A benchmark, not a test: it asserts nothing and its numbers depend on the machine.
//!
//! What is timed is `spp` samples per pixel of a fresh film, after a warm-up that is reported
//! on its own: for the GPU the kernel's compilation (naga, then the driver's JIT) and one
//! 1-spp pass, for the CPU one 1-spp pass (thread start-up, page faults). Camera paths/s is
//! width · height · spp / seconds. Rays (closest-hit and shadow) are counted by the CPU
//! integrator; the GPU draws the very same random streams, so its rays per path is measured by
//! the CPU on the first samples of the same streams rather than with atomics in the kernel.

use crate::accel::bvh::Traversal;
use crate::cpu::shadow_probe::shadow_threshold_for;
use crate::film::Film;
use crate::gpu::{Checks, Gpu, GpuRenderer, Residency};
use crate::layout::FlatScene;
use crate::math::sampling::SamplerKind;
use crate::render::{Backend, CpuBackend};
use crate::scene::Scene;
use crate::transport::camera::Camera;
use crate::transport::faults::Faults;
use crate::transport::method::Method;
use anyhow::{Context, Result};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// Which backend a benchmark row ran on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Which {
    Cpu,
    Gpu,
}

impl Which {
    /// The traversal this backend's BVH is built for (`FlatScene::build`).
    pub fn traversal(self) -> Traversal {
        match self {
            Which::Cpu => CpuBackend::TRAVERSAL,
            Which::Gpu => GpuRenderer::TRAVERSAL,
        }
    }
}

/// What to run.
#[derive(Clone, Debug)]
pub struct Config {
    pub scenes: Vec<PathBuf>,
    pub backends: Vec<Which>,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u32,
    /// The methods to time, each on every scene and backend.
    pub methods: Vec<Method>,
    /// The samplers to time, each on every scene, method and backend (`--sampler`).
    pub samplers: Vec<SamplerKind>,
    pub light_samples: u32,
    pub threads: usize,
}

/// One scene on one backend.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub scene: String,
    pub triangles: usize,
    pub spheres: usize,
    pub backend: Which,
    #[serde(serialize_with = "method_name")]
    pub method: Method,
    pub sampler: SamplerKind,
    pub device: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub light_samples: u32,
    /// Wall seconds of the timed samples.
    pub seconds: f64,
    pub camera_paths_per_second: f64,
    /// Closest-hit plus shadow rays per camera path (light tracing and BDPT: per pixel and
    /// iteration, the light subpath's rays included; see the module comment).
    pub rays_per_path: f64,
    pub rays_per_second: f64,
    /// Kernel compilation (GPU only; 0 on the CPU).
    pub compile_seconds: f64,
    /// The untimed first 1-spp pass.
    pub warmup_seconds: f64,
    pub image_mean: [f64; 3],
}

/// The whole run, as written to JSON.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub hexray_version: String,
    pub date_utc: String,
    pub machine: String,
    pub rows: Vec<Row>,
}

/// Runs every scene on every backend, calling `on_row` as each finishes. A GPU row needs `gpu`.
pub fn run(config: &Config, gpu: Option<&Gpu>, mut on_row: impl FnMut(&Row)) -> Result<Report> {
    let mut rows = Vec::new();
    for path in &config.scenes {
        let scene = Scene::load(path).map_err(|e| anyhow::anyhow!("{e}"))?;
        // The scene flattened for each backend, whose BVHs differ in large scenes.
        let flats: Vec<FlatScene> = config
            .backends
            .iter()
            .map(|which| FlatScene::build(&scene, which.traversal()))
            .collect();
        let Some(first) = flats.first() else {
            continue;
        };
        let camera = Camera::new(&scene.desc.camera, config.width, config.height);
        for &method in &config.methods {
            // Rays per path on the first samples of the streams every backend draws (the
            // same rays whichever tree finds their hits).
            let probe_spp = config.spp.min(4);
            let mut probe = CpuBackend::new(first, camera, config.seed, config.threads)?;
            probe.light_samples = config.light_samples;
            probe.method = method;
            probe.pass(0, probe_spp, &mut Film::new(config.width, config.height))?;
            let paths = |spp: u32| config.width as f64 * config.height as f64 * spp as f64;
            let rays_per_path = probe.rays as f64 / paths(probe_spp);

            for (&which, flat) in config.backends.iter().zip(&flats) {
                let (mut backend, compile_seconds) = make_backend(
                    which,
                    flat,
                    camera,
                    config.seed,
                    method,
                    config.light_samples,
                    config.threads,
                    gpu,
                )?;
                let warm = Instant::now();
                backend.pass(0, 1, &mut Film::new(config.width, config.height))?;
                let warmup_seconds = warm.elapsed().as_secs_f64();

                for &sampler in &config.samplers {
                    let mut film = Film::new(config.width, config.height).with_sampler(sampler);
                    let start = Instant::now();
                    backend.pass(0, config.spp, &mut film)?;
                    let seconds = start.elapsed().as_secs_f64();
                    let row = Row {
                        scene: scene.desc.name.clone(),
                        triangles: flat.triangles.len(),
                        spheres: flat.spheres.len(),
                        backend: which,
                        method,
                        sampler,
                        device: backend.device(),
                        width: config.width,
                        height: config.height,
                        spp: config.spp,
                        light_samples: config.light_samples,
                        seconds,
                        camera_paths_per_second: paths(config.spp) / seconds,
                        rays_per_path,
                        rays_per_second: rays_per_path * paths(config.spp) / seconds,
                        compile_seconds,
                        warmup_seconds,
                        image_mean: film.image_mean().0,
                    };
                    on_row(&row);
                    rows.push(row);
                }
            }
        }
    }
    Ok(Report {
        hexray_version: env!("CARGO_PKG_VERSION").into(),
        date_utc: utc_date(),
        machine: machine(),
        rows,
    })
}

/// A backend of either kind with the CLI's defaults (unchecked kernel, preferred residency),
/// and the seconds spent building it (the GPU kernel's compilation; 0 for the CPU).
#[allow(clippy::too_many_arguments)]
pub fn make_backend<'a>(
    which: Which,
    flat: &'a FlatScene,
    camera: Camera,
    seed: u32,
    method: Method,
    light_samples: u32,
    threads: usize,
    gpu: Option<&Gpu>,
) -> Result<(Box<dyn Backend + 'a>, f64)> {
    let start = Instant::now();
    Ok(match which {
        Which::Cpu => {
            let mut b = CpuBackend::new(flat, camera, seed, threads)?;
            b.light_samples = light_samples;
            b.method = method;
            (Box::new(b), 0.0)
        }
        Which::Gpu => {
            let g = gpu.context("the GPU backend needs a GPU adapter")?;
            let mut renderer = GpuRenderer::new(
                &g.device,
                &g.queue,
                flat,
                camera,
                seed,
                Faults::NONE,
                Checks::Unchecked,
                Residency::preferred(&g.info, &g.device.limits(), flat),
                method,
                shadow_threshold_for(method, flat, &camera),
                None,
            )?;
            renderer.set_light_samples(light_samples);
            if method.progressive() {
                let base =
                    crate::transport::merging::MergeRadius::default_for(flat, &camera, method);
                renderer.set_merge_radius(crate::gpu::context::default_merge_radius(&g.info, base));
            }
            let b = crate::render::GpuBackend {
                renderer,
                adapter: crate::gpu::context::describe(&g.info),
            };
            (Box::new(b), start.elapsed().as_secs_f64())
        }
    })
}

fn method_name<S: serde::Serializer>(m: &Method, s: S) -> std::result::Result<S::Ok, S::Error> {
    s.serialize_str(m.name())
}

/// The CPU model and the number of cores the process may use, e.g. "AMD EPYC 9B14, 2 cores".
pub fn machine() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{model}, {cores} cores")
}

/// Today's date in UTC as YYYY-MM-DD (Howard Hinnant's civil-from-days algorithm).
pub fn utc_date() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let z = (secs / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

/// The rows as an aligned text table.
pub fn table(report: &Report) -> String {
    let mut s = format!(
        "hexray {} bench, {}, {}\n{:<16} {:<4} {:<6} {:<11} {:>9} {:>5} {:>9} {:>11} {:>9} {:>10} {:>9} {:>9}  device\n",
        report.hexray_version,
        report.machine,
        report.date_utc,
        "scene",
        "be",
        "method",
        "sampler",
        "size",
        "spp",
        "seconds",
        "M paths/s",
        "rays/path",
        "M rays/s",
        "compile s",
        "warmup s"
    );
    for r in &report.rows {
        s += &format!(
            "{:<16} {:<4} {:<6} {:<11} {:>9} {:>5} {:>9.3} {:>11.3} {:>9.2} {:>10.3} {:>9.3} {:>9.3}  {}\n",
            r.scene,
            match r.backend {
                Which::Cpu => "cpu",
                Which::Gpu => "gpu",
            },
            r.method.name(),
            r.sampler.name(),
            format!("{}x{}", r.width, r.height),
            r.spp,
            r.seconds,
            r.camera_paths_per_second / 1e6,
            r.rays_per_path,
            r.rays_per_second / 1e6,
            r.compile_seconds,
            r.warmup_seconds,
            r.device
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_date_is_a_plausible_calendar_date() {
        let d = utc_date();
        let parts: Vec<u32> = d.split('-').map(|p| p.parse().unwrap()).collect();
        assert_eq!(parts.len(), 3, "{d}");
        assert!(parts[0] >= 2024 && (1..=12).contains(&parts[1]) && (1..=31).contains(&parts[2]));
    }
}
