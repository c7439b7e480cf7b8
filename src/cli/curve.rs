//! `hexray curve`: relMSE against time and spp, as CSV and charts.

use super::*;
use anyhow::{Context, Result};
use clap::Args;
use hexray::film::output;
use hexray::layout::FlatScene;
use hexray::math::sampling::SamplerKind;
use hexray::scene::Scene;
use hexray::transport::camera::Camera;
use hexray::transport::method::Method;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args, Debug, Clone)]
pub(crate) struct CurveArgs {
    /// Scene file (JSON).
    pub(crate) scene: PathBuf,
    /// The reference image (.exr or .npy); its size is the curve's resolution.
    #[arg(long)]
    pub(crate) reference: PathBuf,
    /// Backends, comma-separated: cpu, gpu.
    #[arg(long, value_delimiter = ',', default_values_t = [BenchBackend::Cpu])]
    pub(crate) backend: Vec<BenchBackend>,
    /// Use the first GPU adapter whose name contains this.
    #[arg(long)]
    pub(crate) adapter: Option<String>,
    /// Render-time budget per series, in seconds.
    #[arg(long, value_parser = parse_seconds, default_value = "10")]
    pub(crate) time: f64,
    /// Methods, comma-separated (path, light, bdpt, sppm, vcm, vcm-full): one series per
    /// backend and method.
    #[arg(long, value_delimiter = ',', default_values_t = [Method::Path])]
    pub(crate) method: Vec<Method>,
    /// Shadow rays per diffuse vertex (path tracing); a comma-separated list gives one series
    /// per value.
    #[arg(long, value_delimiter = ',', default_values_t = [1u32])]
    pub(crate) light_samples: Vec<u32>,
    /// Samplers, comma-separated (independent, sobol): one series per value.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [SamplerKind::Independent])]
    pub(crate) sampler: Vec<SamplerKind>,
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u32,
    /// CPU threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub(crate) threads: Option<u32>,
    /// Another renderer's curve to overlay (CSV: scene,variant,spp,seconds,rmse,relmse; one
    /// series per variant); may be given more than once.
    #[arg(long)]
    pub(crate) overlay: Vec<PathBuf>,
    /// The overlay rows to use (default: the scene's name).
    #[arg(long)]
    pub(crate) overlay_scene: Option<String>,
    /// The overlaid renderer's name in the legend.
    #[arg(long, default_value = "mitsuba")]
    pub(crate) overlay_name: String,
    /// Output directory: curve.csv, relmse_vs_seconds.{png,svg}, relmse_vs_spp.{png,svg}.
    #[arg(long)]
    pub(crate) out: PathBuf,
}

pub(crate) fn curve(args: &CurveArgs) -> Result<ExitCode> {
    use hexray::analysis::bench::{make_backend, Which};
    use hexray::analysis::chart::{relmse_chart, XAxis};
    let scene = match Scene::load(&args.scene) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return Ok(ExitCode::from(EXIT_BAD_INPUT));
        }
    };
    let reference = match hexray::analysis::compare::read_image(&args.reference) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: --reference: {e:#}");
            return Ok(ExitCode::from(EXIT_BAD_INPUT));
        }
    };
    if let Some(&n) = args
        .light_samples
        .iter()
        .find(|&&n| n == 0 || n > hexray::math::sampling::MAX_LIGHT_SAMPLES)
    {
        eprintln!(
            "error: --light-samples {n}: give 1 to {}",
            hexray::math::sampling::MAX_LIGHT_SAMPLES
        );
        return Ok(ExitCode::from(EXIT_BAD_INPUT));
    }
    let mut overlay = Vec::new();
    for o in &args.overlay {
        let name = args
            .overlay_scene
            .clone()
            .unwrap_or(scene.desc.name.clone());
        let rows = match hexray::analysis::curve::read_overlay(o, &name, &args.overlay_name) {
            Ok(v) => v,
            Err(e) => {
                eprintln!("error: --overlay: {e:#}");
                return Ok(ExitCode::from(EXIT_BAD_INPUT));
            }
        };
        if rows.is_empty() {
            eprintln!(
                "error: --overlay {}: no rows for scene `{name}` (choose with --overlay-scene)",
                o.display()
            );
            return Ok(ExitCode::from(EXIT_BAD_INPUT));
        }
        overlay.extend(rows);
    }
    let wants_gpu = args.backend.contains(&BenchBackend::Gpu);
    let gpu = match gpu_if(wants_gpu, args.adapter.as_deref()) {
        Ok(g) => g,
        Err(code) => return Ok(code),
    };
    let (w, h) = (reference.width as u32, reference.height as u32);
    let camera = Camera::new(&scene.desc.camera, w, h);
    let threads = args.threads.map_or_else(
        || std::thread::available_parallelism().map_or(1, |n| n.get()),
        |t| t as usize,
    );
    let mut points = Vec::new();
    let mut devices = Vec::new();
    for b in &args.backend {
        let which = match b {
            BenchBackend::Cpu => Which::Cpu,
            BenchBackend::Gpu => Which::Gpu,
        };
        let flat = FlatScene::build(&scene, which.traversal());
        for &method in &args.method {
            // Several shadow-ray counts are path tracing's alone.
            let counts: &[u32] = if method == Method::Path {
                &args.light_samples
            } else {
                &[1]
            };
            for (&n, &sampler) in counts
                .iter()
                .flat_map(|n| args.sampler.iter().map(move |s| (n, s)))
            {
                let (mut backend, compile) = make_backend(
                    which,
                    &flat,
                    camera,
                    args.seed,
                    method,
                    n,
                    threads,
                    gpu.as_ref(),
                )?;
                // The adapter's name without its (type, API, driver) suffix, to fit the caption.
                let device = backend.device();
                let short = device
                    .find(") (")
                    .map_or(device.as_str(), |i| &device[..=i]);
                let entry = format!("{}: {short}", backend.name());
                if !devices.contains(&entry) {
                    devices.push(entry);
                }
                let (mut series, warmup) = hexray::analysis::curve::measure(
                    &scene.desc.name,
                    backend.as_mut(),
                    sampler,
                    w,
                    h,
                    &reference,
                    args.time,
                    |p| {
                        eprintln!(
                            "{} {:>6} spp {:>9.3} s  RMSE {:.4e}  relMSE {:.4e}",
                            p.backend, p.spp, p.seconds, p.rmse, p.relmse
                        )
                    },
                )?;
                eprintln!(
                    "{} {method}: kernel build {compile:.2} s, warm-up pass {warmup:.2} s (not counted)",
                    backend.name()
                );
                for p in &mut series {
                    if args.method.len() > 1 {
                        p.backend = format!("{} {method}", p.backend);
                    }
                    if args.sampler.len() > 1 {
                        p.backend = format!("{}, {sampler}", p.backend);
                    }
                    if args.light_samples.len() > 1 && method == Method::Path {
                        p.backend = format!(
                            "{}, {n} shadow ray{}",
                            p.backend,
                            if n == 1 { "" } else { "s" }
                        );
                    }
                }
                points.extend(series);
            }
        }
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    output::write_text(
        &args.out.join("curve.csv"),
        &hexray::analysis::curve::csv(&points),
    )?;
    let mut all = points.clone();
    all.extend(overlay);
    let caption = format!(
        "{}x{} · {} · {} · {}",
        w,
        h,
        hexray::analysis::bench::machine(),
        devices.join("; "),
        hexray::analysis::bench::utc_date()
    );
    let title = format!("{}: relMSE against", scene.desc.name);
    relmse_chart(
        &all,
        XAxis::Seconds,
        &format!("{title} render time"),
        &caption,
        &args.out.join("relmse_vs_seconds"),
    )?;
    relmse_chart(
        &all,
        XAxis::Spp,
        &format!("{title} samples per pixel"),
        &caption,
        &args.out.join("relmse_vs_spp"),
    )?;
    eprintln!(
        "wrote {}/curve.csv, relmse_vs_seconds.png/.svg, relmse_vs_spp.png/.svg",
        args.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
