//! `hexray bench`: camera paths/s per scene and backend.

use super::*;
use anyhow::Result;
use clap::Args;
use hexray::film::output;
use hexray::math::sampling::SamplerKind;
use hexray::scene::Scene;
use hexray::transport::method::Method;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args, Debug, Clone)]
pub(crate) struct BenchArgs {
    /// Scene files (default: the three reference scenes).
    #[arg(default_values_t = [
        "scenes/tncg15_room.json".to_string(),
        "scenes/cornell_box.json".to_string(),
        "scenes/glass_room.json".to_string(),
    ])]
    pub(crate) scenes: Vec<String>,
    /// Backends, comma-separated: cpu, gpu. A gpu row needs an adapter.
    #[arg(long, value_delimiter = ',', default_values_t = [BenchBackend::Cpu, BenchBackend::Gpu])]
    pub(crate) backend: Vec<BenchBackend>,
    /// Use the first GPU adapter whose name contains this.
    #[arg(long)]
    pub(crate) adapter: Option<String>,
    /// Samples per pixel of the timed render.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) spp: u32,
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub(crate) width: u32,
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub(crate) height: u32,
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u32,
    /// Methods, comma-separated (path, light, bdpt, sppm, vcm, vcm-full): a row for each on
    /// every scene and backend.
    #[arg(long, value_delimiter = ',', default_values_t = [Method::Path])]
    pub(crate) method: Vec<Method>,
    /// Samplers, comma-separated (independent, sobol): a row for each on every scene, method
    /// and backend, one after the other.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [SamplerKind::Independent])]
    pub(crate) sampler: Vec<SamplerKind>,
    /// Shadow rays per diffuse vertex (path tracing).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=hexray::math::sampling::MAX_LIGHT_SAMPLES as i64))]
    pub(crate) light_samples: u32,
    /// CPU threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub(crate) threads: Option<u32>,
    /// Where the JSON report goes.
    #[arg(long, default_value = "out/bench.json")]
    pub(crate) out: PathBuf,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum BenchBackend {
    Cpu,
    Gpu,
}

impl std::fmt::Display for BenchBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            BenchBackend::Cpu => "cpu",
            BenchBackend::Gpu => "gpu",
        })
    }
}

/// A timed render shorter than this is reported as too short to time well.
const SHORT_ROW_SECONDS: f64 = 0.25;

pub(crate) fn bench(args: &BenchArgs) -> Result<ExitCode> {
    use hexray::analysis::bench::{self, Which};
    for s in &args.scenes {
        if let Err(e) = Scene::load(std::path::Path::new(s)) {
            eprintln!("error: {e}");
            return Ok(ExitCode::from(EXIT_BAD_INPUT));
        }
    }
    let backends: Vec<Which> = args
        .backend
        .iter()
        .map(|b| match b {
            BenchBackend::Cpu => Which::Cpu,
            BenchBackend::Gpu => Which::Gpu,
        })
        .collect();
    let gpu = match gpu_if(backends.contains(&Which::Gpu), args.adapter.as_deref()) {
        Ok(g) => g,
        Err(code) => return Ok(code),
    };
    let config = bench::Config {
        scenes: args.scenes.iter().map(PathBuf::from).collect(),
        backends,
        width: args.width,
        height: args.height,
        spp: args.spp,
        seed: args.seed,
        methods: args.method.clone(),
        samplers: args.sampler.clone(),
        light_samples: args.light_samples,
        threads: args.threads.map_or_else(
            || std::thread::available_parallelism().map_or(1, |n| n.get()),
            |t| t as usize,
        ),
    };
    let report = bench::run(&config, gpu.as_ref(), |row| {
        eprintln!(
            "{} with {} ({} sampler) on {}: {:.3} M camera paths/s ({:.2} s for {} spp; warm-up {:.2} s apart)",
            row.scene,
            row.method,
            row.sampler,
            row.device,
            row.camera_paths_per_second / 1e6,
            row.seconds,
            row.spp,
            row.compile_seconds + row.warmup_seconds
        );
    })?;
    print!("{}", bench::table(&report));
    // A short row times the start-up of a render more than its throughput: on an NVIDIA H100,
    // path tracing 256x256 at 64 spp took 38 ms at 109 M camera paths/s, against 352 M/s over
    // 6 s (docs/journal/2026-11-26_h100.md): per-pass readbacks and the first pass's small dispatches weigh there.
    let short: Vec<f64> = report
        .rows
        .iter()
        .map(|r| r.seconds)
        .filter(|&s| s < SHORT_ROW_SECONDS)
        .collect();
    if let Some(least) = short.iter().copied().reduce(f64::min) {
        eprintln!(
            "hexray: warning: {} of {} rows took under {SHORT_ROW_SECONDS} s (the shortest \
             {least:.3} s), too short to time a backend's throughput well; raise --spp",
            short.len(),
            report.rows.len()
        );
    }
    output::write_text(&args.out, &serde_json::to_string_pretty(&report)?)?;
    eprintln!("wrote {}", args.out.display());
    Ok(ExitCode::SUCCESS)
}
