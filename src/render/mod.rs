//! Progressive rendering, common to both backends: passes of a few samples per pixel until the
//! sample count or the time budget is reached, or the user stops it; the samples taken so far
//! are kept in every case.

use crate::film::Film;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

pub mod adaptive;
mod cpu_backend;
mod gpu_backend;

pub use cpu_backend::CpuBackend;
pub use gpu_backend::GpuBackend;

/// Something that can add samples `first..first + count` of every pixel to a film.
pub trait Backend {
    /// A short name for logs and metadata ("cpu", "gpu").
    fn name(&self) -> &'static str;
    /// The device it runs on, for logs and metadata.
    fn device(&self) -> String;
    /// Adds samples `first..first + count` until `stop` is set: a backend stopped under way
    /// adds only the samples it finished whole (each pixel as many) and returns early; the
    /// caller reads how many from the film.
    fn pass_until(
        &mut self,
        first: u32,
        count: u32,
        film: &mut Film,
        stop: &AtomicBool,
    ) -> anyhow::Result<()>;
    /// Adds each run's samples to its pixel, weighted by the run's weight (adaptive sampling,
    /// [`adaptive`]), until `stop` is set: a backend stopped under way drops the pass whole.
    /// Backends and methods without adaptive sampling refuse.
    fn adaptive_pass_until(
        &mut self,
        runs: &[adaptive::PixelRun],
        film: &mut Film,
        stop: &AtomicBool,
    ) -> anyhow::Result<()> {
        let _ = (runs, film, stop);
        anyhow::bail!("adaptive sampling is not available on this backend for this method")
    }
    /// The whole pass: [`Backend::pass_until`] with no stop.
    fn pass(&mut self, first: u32, count: u32, film: &mut Film) -> anyhow::Result<()> {
        self.pass_until(first, count, film, &AtomicBool::new(false))
    }
    /// What the method chose or met that an image's provenance should say (`key`, value), for
    /// the EXR metadata and the log.
    fn provenance(&self) -> Vec<(&'static str, String)> {
        Vec::new()
    }
}

/// When to stop: after `spp` samples per pixel, after `seconds`, or once the image's estimated
/// relMSE is at most `relmse`, whichever comes first (at least one of them is set).
#[derive(Clone, Copy, Debug, Default)]
pub struct Budget {
    pub spp: Option<u32>,
    pub seconds: Option<f64>,
    /// The error target (`--target-error`): [`Film::estimated_relmse`], looked at from
    /// [`MIN_SAMPLES_FOR_TARGET`] samples per pixel on.
    pub relmse: Option<f64>,
}

/// Samples per pixel before an error target is looked at: a pixel's variance from fewer
/// samples is too often far below its true value (a few paths that find a small light, and none
/// yet that do), and the render would stop too early.
pub const MIN_SAMPLES_FOR_TARGET: u64 = 16;

/// Why a render ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum StopReason {
    SampleCount,
    TimeBudget,
    /// The estimated relMSE reached the error target.
    ErrorTarget,
    Interrupted,
    /// The backend failed (e.g. the GPU device was lost); the film holds every pass before.
    Failed(String),
}

/// What a progressive render did.
#[derive(Clone, Debug)]
pub struct RenderReport {
    pub spp: u32,
    pub seconds: f64,
    pub reason: StopReason,
    /// The first pass of this session, reported apart: it carries what a session pays once
    /// (a GPU driver's compilation of the kernel at its first dispatch, the thread pool's start).
    pub first_pass: Option<FirstPass>,
}

/// The first completed pass of a session: its samples per pixel (the mean over the pixels for
/// an adaptive render) and its seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstPass {
    pub spp: f64,
    pub seconds: f64,
}

/// A pass aims at this duration, so that Ctrl-C and a time budget take effect promptly.
const TARGET_PASS_SECONDS: f64 = 0.25;

/// Runs passes until the budget is spent, `stop` is set or the backend fails; the samples of
/// every completed pass stay in `film` in all cases, and of a pass that `stop` cuts short, those
/// the backend finished whole ([`Backend::pass_until`]). `on_pass(film, spp_done, elapsed)` is
/// called after each pass (progress, checkpoints).
pub fn render_progressive(
    backend: &mut dyn Backend,
    film: &mut Film,
    budget: Budget,
    stop: &AtomicBool,
    mut on_pass: impl FnMut(&Film, u32, f64),
) -> RenderReport {
    assert!(budget.spp.is_some() || budget.seconds.is_some() || budget.relmse.is_some());
    let start = Instant::now();
    let mut done = film.spp() as u32;
    let target = budget.spp.map(|s| done + s);
    let mut per_spp = None::<f64>;
    let mut first_pass = None;
    let reason = loop {
        if stop.load(Ordering::SeqCst) {
            break StopReason::Interrupted;
        }
        let elapsed = start.elapsed().as_secs_f64();
        if target.is_some_and(|t| done >= t) {
            break StopReason::SampleCount;
        }
        if budget.seconds.is_some_and(|s| elapsed >= s) {
            break StopReason::TimeBudget;
        }
        let needed = match error_target(film, budget, done) {
            ErrorTarget::Reached => break StopReason::ErrorTarget,
            ErrorTarget::Needs(n) => n,
        };
        let count = pass_size(per_spp, budget, elapsed, target.map(|t| t - done), needed);
        let t0 = Instant::now();
        let before = film.spp();
        if let Err(e) = backend.pass_until(done, count, film, stop) {
            break StopReason::Failed(format!("{e:#}"));
        }
        let added = (film.spp() - before) as u32;
        if added < count {
            // Stopped under way: the samples finished whole are kept.
            done += added;
            if added > 0 {
                on_pass(film, done, start.elapsed().as_secs_f64());
            }
            break StopReason::Interrupted;
        }
        let dt = t0.elapsed().as_secs_f64();
        // The first pass includes warm-up (thread pool start, shader compilation): measure
        // the cost again on every pass and keep the latest.
        per_spp = Some(dt / count as f64);
        first_pass.get_or_insert(FirstPass {
            spp: count as f64,
            seconds: dt,
        });
        done += count;
        on_pass(film, done, start.elapsed().as_secs_f64());
    };
    RenderReport {
        spp: film.spp() as u32,
        seconds: start.elapsed().as_secs_f64(),
        reason,
        first_pass,
    }
}

/// Where a render stands against its error target.
enum ErrorTarget {
    Reached,
    /// Not reached (or none set): at most this many more samples per pixel in the next pass.
    Needs(Option<u32>),
}

/// The error target: were relMSE to fall as 1 / n, the samples it needs would be about
/// n · (estimate / target − 1) more, `done` = n samples per pixel so far. It falls faster under
/// the Sobol sampler, so the pass takes half of those, and the render closes in on the target
/// rather than overshoot it. Looked at from [`MIN_SAMPLES_FOR_TARGET`] samples per pixel on.
fn error_target(film: &Film, budget: Budget, done: u32) -> ErrorTarget {
    let Some(target) = budget.relmse else {
        return ErrorTarget::Needs(None);
    };
    if (done as u64) < MIN_SAMPLES_FOR_TARGET {
        return ErrorTarget::Needs(Some(MIN_SAMPLES_FOR_TARGET as u32 - done));
    }
    let estimate = film.estimated_relmse().unwrap_or(f64::INFINITY);
    if estimate <= target {
        return ErrorTarget::Reached;
    }
    let more = (done as f64 * (estimate / target - 1.0) / 2.0).ceil();
    ErrorTarget::Needs(Some(more.clamp(1.0, u32::MAX as f64) as u32))
}

/// Samples per pixel of the next pass, from the measured cost of one (`per_spp` seconds): one
/// first, then as many as fit in the target duration, in what remains of the time budget, of
/// the samples (`remaining`) and of what the error target needs.
fn pass_size(
    per_spp: Option<f64>,
    budget: Budget,
    elapsed: f64,
    remaining: Option<u32>,
    needed: Option<u32>,
) -> u32 {
    let mut count = match per_spp {
        None => 1,
        Some(c) => {
            let mut secs = TARGET_PASS_SECONDS;
            if let Some(s) = budget.seconds {
                secs = secs.min(s - elapsed);
            }
            ((secs / c).floor() as u32).max(1)
        }
    };
    if let Some(r) = remaining {
        count = count.min(r);
    }
    if let Some(n) = needed {
        count = count.min(n);
    }
    count
}

/// Light vertices per light subpath assumed by [`host_bytes_per_pixel`]: well above the mean
/// subpath length of the reference scenes (Russian roulette ends most subpaths within 3-5
/// bounces), since the buffer grows to the longest iteration.
const LIGHT_VERTICES_PER_PIXEL: u64 = 8;

/// An estimate of the host memory a render holds per pixel, for the check before a render
/// starts: the film's f64 sums, the EXR, variance and PNG images, and for the methods that trace
/// light subpaths the splat film, n_c per pixel, the light vertices (one subpath per pixel) and
/// the hash grid over them.
pub fn host_bytes_per_pixel(method: crate::transport::method::Method) -> u64 {
    use std::mem::size_of;
    let film = size_of::<crate::film::PixelStats>() as u64;
    let outputs = 2 * size_of::<[f32; 3]>() as u64 + 3;
    let mut bytes = film + outputs;
    if method.splats() {
        let vertices = LIGHT_VERTICES_PER_PIXEL
            * (size_of::<crate::transport::subpath::LightVertex>() + size_of::<[f32; 4]>() + 4)
                as u64;
        bytes += size_of::<crate::transport::splat::SplatCell>() as u64 + 4 + 4 + vertices;
    }
    bytes
}

/// Memory the system can give without swapping (Linux's MemAvailable), if known.
pub fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}
