//! The `hexray` command line: one module per subcommand, and the options and exit statuses
//! they share, defined once here. Everything else lives in the library.

pub mod bench;
pub mod compare;
pub mod curve;
pub mod info;
pub mod merge;
pub mod render;

pub(crate) use bench::*;
pub(crate) use compare::*;
pub(crate) use curve::*;
pub(crate) use info::*;
pub(crate) use merge::*;
pub(crate) use render::*;

use clap::{Parser, Subcommand, ValueEnum};
use hexray::transport::method::Method;
use std::path::PathBuf;
use std::process::ExitCode;

/// Exit status for bad input (scene or arguments), as clap uses for usage errors.
pub(crate) const EXIT_BAD_INPUT: u8 = 2;

#[derive(Parser, Debug)]
#[command(
    name = "hexray",
    version,
    about = "A physically based Monte Carlo path tracer (WGSL compute shader + CPU reference)",
    args_conflicts_with_subcommands = true
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Option<Command>,
    /// `render` is the default subcommand: `hexray --backend cpu` renders the default scene.
    #[command(flatten)]
    pub(crate) render: RenderArgs,
}

#[derive(Subcommand, Debug)]
pub(crate) enum Command {
    /// Render a scene to EXR (linear) + PNG (sRGB) [default].
    Render(RenderArgs),
    /// List the GPU adapters wgpu finds, with backend, driver and limits; with a scene, describe
    /// the scene instead (triangles, bounds, BVH, memory per backend, build time) without
    /// rendering.
    Info(InfoArgs),
    /// Render a high-spp reference: an EXR and its variance EXR (default out/<name>_ref.exr).
    Reference(RenderArgs),
    /// Compare a render with a reference: means, ratio, RMSE, relMSE, z-scores.
    Compare(CompareArgs),
    /// Error against time: relMSE after each doubling of spp, per backend, as CSV and charts.
    Curve(CurveArgs),
    /// Merge renders of one scene made with different seeds into one (spp-weighted).
    Merge(MergeArgs),
    /// Benchmark: each scene on each backend at fixed spp; camera paths/s, rays/s, warm-up apart.
    Bench(BenchArgs),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum BackendChoice {
    /// A hardware GPU when wgpu finds one, else the CPU backend (also when the only adapter is a
    /// software one such as lavapipe, which runs slower on the same cores).
    Auto,
    /// The CPU reference renderer (rayon over tiles).
    Cpu,
    /// The WGSL compute-shader renderer (wgpu).
    Gpu,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum ResidencyChoice {
    Storage,
    Uniform,
}

pub(crate) fn parse_seconds(s: &str) -> std::result::Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{e}"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err("the time budget must be a positive number of seconds".into())
    }
}

pub(crate) fn parse_target_error(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("expected a relMSE above 0, found {s:?}")),
    }
}

pub(crate) fn parse_exposure(s: &str) -> std::result::Result<f32, String> {
    match s.parse::<f32>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(format!("expected a finite number of stops, found {s:?}")),
    }
}

pub(crate) fn parse_radius(s: &str) -> std::result::Result<f32, String> {
    let v: f32 = s.parse().map_err(|e| format!("{e}"))?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err("the merge radius must be a finite number >= 0 (scene units)".into())
    }
}

pub(crate) fn parse_patch_size(s: &str) -> std::result::Result<f32, String> {
    let v: f32 = s.parse().map_err(|e| format!("{e}"))?;
    if v.is_finite() && v > 0.0 && v <= 1.0 {
        Ok(v)
    } else {
        Err("the patch size is a share of the scene's diagonal, in (0, 1]".into())
    }
}

pub(crate) fn parse_alpha(s: &str) -> std::result::Result<f32, String> {
    let v: f32 = s.parse().map_err(|e| format!("{e}"))?;
    if v > 0.0 && v <= 1.0 {
        Ok(v)
    } else {
        Err("alpha must be in (0, 1]".into())
    }
}

/// Parses the command line and runs the subcommand; the exit status follows docs/usage.md's table.
pub fn run() -> ExitCode {
    let cli = Cli::parse();
    let args = match cli.command {
        Some(Command::Render(a)) => a,
        Some(Command::Info(InfoArgs { scene: None })) => return info(),
        Some(Command::Info(InfoArgs { scene: Some(s) })) => return scene_info(&s),
        Some(Command::Compare(c)) => return compare(&c),
        Some(Command::Curve(c)) => {
            return match curve(&c) {
                Ok(code) => code,
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::FAILURE
                }
            }
        }
        Some(Command::Reference(mut r)) => {
            // A reference is a render with its variance, a long default and its own name.
            r.variance = true;
            // A reference must be unbiased: path tracing unless asked otherwise.
            r.method.get_or_insert(Method::Path);
            if r.spp.is_none() && r.time.is_none() {
                r.spp = Some(1024);
            }
            if r.out.is_none() {
                let stem = r
                    .scene_path()
                    .file_stem()
                    .map_or("render".into(), |s| s.to_string_lossy().into_owned());
                r.out = Some(PathBuf::from("out").join(format!("{stem}_ref.exr")));
            }
            r
        }
        Some(Command::Merge(m)) => {
            return match merge(&m) {
                Ok(code) => code,
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::FAILURE
                }
            }
        }
        Some(Command::Bench(b)) => {
            return match bench(&b) {
                Ok(code) => code,
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::FAILURE
                }
            }
        }
        None => cli.render,
    };
    match render(&args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// The GPU for `--backend gpu` when `wanted`, or the exit status for a missing adapter.
pub(crate) fn gpu_if(
    wanted: bool,
    adapter: Option<&str>,
) -> Result<Option<hexray::gpu::Gpu>, ExitCode> {
    if !wanted {
        return Ok(None);
    }
    hexray::gpu::acquire(adapter).map(Some).map_err(|e| {
        eprintln!("error: --backend gpu: {e}");
        ExitCode::from(EXIT_BAD_INPUT)
    })
}
