//! `hexray render` and `hexray reference`: the options, the checks before any work, the progressive
//! render with its progress and checkpoints, resuming, and the outputs.

use super::*;
use anyhow::{Context, Result};
use clap::Args;
use hexray::cpu::dark_image::dark_image_warning;
use hexray::film::file::{self as film_file, FilmIdentity};
use hexray::film::output::{self, Metadata, RgbImage};
use hexray::film::Film;
use hexray::gpu;
use hexray::interrupt::StopRequest;
use hexray::layout::FlatScene;
use hexray::math::sampling::SamplerKind;
use hexray::render::adaptive::{render_adaptive, AdaptiveSettings};
use hexray::render::{render_progressive, Backend, Budget, CpuBackend, StopReason};
use hexray::scene::Scene;
use hexray::transport::camera::Camera;
use hexray::transport::method::Method;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Args, Debug, Clone)]
pub(crate) struct RenderArgs {
    /// Scene file (JSON) [default: scenes/tncg15_room.json, or its copy built into hexray
    /// where that file is absent; with --resume, the resumed render's scene].
    pub(crate) scene: Option<PathBuf>,
    /// Which renderer to use.
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    pub(crate) backend: BackendChoice,
    /// Use the first GPU adapter whose name contains this (see `hexray info`).
    #[arg(long)]
    pub(crate) adapter: Option<String>,
    /// Compile the kernel with naga's runtime checks (bounds checks, loop bounding). Off by
    /// default: see docs/design/gpu.md for the measurement behind that choice.
    #[arg(long)]
    pub(crate) shader_checks: bool,
    /// Where the GPU keeps the scene arrays (default: uniform buffers on CPU adapters when the
    /// scene fits, else storage buffers).
    #[arg(long, value_enum)]
    pub(crate) scene_residency: Option<ResidencyChoice>,
    /// Light-transport method. `light` sees nothing through mirrors or glass (those surfaces
    /// stay black); `light`, `bdpt`, `sppm`, `vcm` and `vcm-full` take one iteration (a light
    /// subpath and a camera subpath per pixel) per sample. `sppm`, `vcm` and `vcm-full` merge
    /// photons: consistent, not unbiased (the bias shrinks with the radius over iterations; the
    /// standard error does not cover it). `whitted` is biased: direct light and perfect mirrors
    /// and glass only, without indirect diffuse light or caustics. `photon-map` is biased: its
    /// density estimates within a fixed radius blur the light, whatever the samples.
    /// `radiosity` is biased: it solves the diffuse light once on patches (--patch-size,
    /// --patch-rays) and takes each patch's indirect light as constant over it; it leaves out
    /// caustics and indirect light by way of mirrors or glass. Default: vcm for `render` (the
    /// lowest error at equal time on the reference scenes, docs/methods.md), path for
    /// `reference` (unbiased).
    #[arg(long, value_enum)]
    pub(crate) method: Option<Method>,
    /// Initial merge radius r_1 of sppm, vcm and vcm-full, in scene units, the same at every
    /// camera vertex; photon-map's radius, the same at every vertex and iteration. Default: a
    /// disk that spans a fixed share of the view's height at the distance that half of the view
    /// lies within (vcm 0.0155 of it, sppm and vcm-full 0.006, photon-map 0.006; for the
    /// progressive methods 0.3 x on a hardware GPU, whose renders run many more iterations); sppm's nearer vertices
    /// merge within that share of the view's height at their own distance.
    /// Iteration i merges within r_1 i^((alpha-1)/2); vcm merges within less where another
    /// surface is nearer to the camera vertex (its clearance, at least 0.1 of that). vcm and
    /// vcm-full with 0 are bdpt.
    #[arg(long, value_parser = parse_radius)]
    pub(crate) radius: Option<f32>,
    /// Radiosity's largest patch, as a share of the diagonal of the scene's bounding box: each
    /// diffuse triangle is cut into n x n sub-triangles and each sphere into bands and sectors
    /// of at most (share x diagonal)² each. Default 0.05 (measured on cornell_box,
    /// docs/methods.md). The dense form-factor matrix takes 4 N² bytes for N patches (each
    /// triangle's two sides are two patches); a scene with more than 16384 patches, or more
    /// than the GPU binds, is refused.
    #[arg(long, value_parser = parse_patch_size)]
    pub(crate) patch_size: Option<f32>,
    /// Radiosity's form-factor rays per patch (default 1024): F_ij is the share of patch i's
    /// cosine-distributed rays that first meet patch j.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1048576))]
    pub(crate) patch_rays: Option<u32>,
    /// The view's reach of a resumed render (`MergeRadius::reach`), taken from its film.
    #[arg(skip)]
    pub(crate) reach: Option<f32>,
    /// Radius reduction alpha of sppm, vcm and vcm-full, in (0, 1] (default 0.75; 1 keeps the
    /// radius).
    #[arg(long, value_parser = parse_alpha)]
    pub(crate) alpha: Option<f32>,
    /// Light subpaths per iteration N of every method but path, whitted and radiosity, at most
    /// one per pixel (more are cut to that): photon-map's photon paths. Default: one per pixel, up to 262144
    /// (512x512) for sppm, vcm, vcm-full and photon-map
    /// and 1048576 for light and bdpt; beyond, the camera subpaths share them (pixel index mod
    /// N), so an iteration's cost grows as its pixels.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) light_paths: Option<u32>,
    /// Shadow rays (light samples) per diffuse vertex, each weighted by multi-sample MIS
    /// (path tracing only).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=hexray::math::sampling::MAX_LIGHT_SAMPLES as i64))]
    pub(crate) light_samples: u32,
    /// Samples per pixel (iterations for the methods with light subpaths). Without --time the
    /// default is 64 for path, whitted and radiosity and 8 for the others (about as long at
    /// 512x512); with --time, no sample limit.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) spp: Option<u32>,
    /// Time budget in seconds: stop after the pass that reaches it, keeping all samples.
    #[arg(long, value_parser = parse_seconds)]
    pub(crate) time: Option<f64>,
    /// Error target: stop once the image's estimated relMSE (mean over pixels of the variance
    /// of the mean over (mean² + 0.01), what `hexray compare` measures against a reference) is
    /// at most E, looked at from 16 samples per pixel on. With --spp or --time, whichever comes
    /// first. A method's bias (merging, whitted, photon-map) is not in the estimate.
    #[arg(long, value_name = "E", value_parser = parse_target_error)]
    pub(crate) target_error: Option<f64>,
    /// Seed of the random streams; renders with different seeds are independent.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u32,
    /// How the random numbers are drawn. independent: a hash per number. sobol: Owen-scrambled
    /// Sobol points (Burley 2020), each pixel's samples two independent randomisations whose
    /// difference gives the standard errors; fewer samples for the same error where the first
    /// bounces' light dominates (docs/sampling.md). Every method; the same points on both
    /// backends.
    #[arg(long, value_enum, default_value_t = SamplerKind::Independent)]
    pub(crate) sampler: SamplerKind,
    /// Adaptive sampling (path tracing): after a uniform first eighth, rounds that each spend as
    /// many samples as all before, given to the pixels in proportion to their estimated relative
    /// error (a quarter spread evenly); each sample is weighted so that the image stays unbiased,
    /// and --spp is then the mean over pixels (docs/sampling.md). It gains where the error is
    /// concentrated (caustics seen directly), little where it is spread over the image.
    #[arg(long)]
    pub(crate) adaptive: bool,
    /// Image width in pixels.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub(crate) width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub(crate) height: u32,
    /// Output EXR path; NAME.png (and NAME_var.exr with --variance) are written beside it.
    /// Default: out/<scene name>.exr.
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Also write the per-pixel variance of the mean as NAME_var.exr.
    #[arg(long)]
    pub(crate) variance: bool,
    /// Exposure of the PNG in stops (the EXR is always linear and unscaled).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = parse_exposure)]
    pub(crate) exposure: f32,
    /// Continue the render NAME.exr (from its film, NAME.film, written beside every render) to
    /// --spp samples in total, or for --time more seconds: same scene (its SHA-1 is checked),
    /// seed, method, size and radius. The new samples continue the random streams, so on the
    /// CPU the result is bit for bit one uninterrupted render of the total. Writes over NAME.*
    /// unless --out says otherwise.
    #[arg(long, value_name = "NAME.exr", conflicts_with_all = ["seed", "sampler", "adaptive", "width", "height", "method", "radius", "alpha", "light_samples", "patch_size", "patch_rays"])]
    pub(crate) resume: Option<PathBuf>,
    /// Also write the outputs (EXR, PNG, film) every SECONDS during the render, atomically, so
    /// that a job killed without warning (SIGKILL, a power cut) loses at most that much.
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub(crate) checkpoint: Option<f64>,
    /// CPU threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub(crate) threads: Option<u32>,
    /// No progress bar and no summary.
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

impl RenderArgs {
    /// The scene file: as given, else the default scene.
    pub(crate) fn scene_path(&self) -> PathBuf {
        self.scene
            .clone()
            .unwrap_or_else(|| PathBuf::from(DEFAULT_SCENE))
    }
}

/// The scene rendered when none is given.
pub(crate) const DEFAULT_SCENE: &str = "scenes/tncg15_room.json";

/// The default scene's file, built into the binary so that `hexray render` works from any
/// folder.
const DEFAULT_SCENE_JSON: &str = include_str!("../../scenes/tncg15_room.json");

/// Loads a scene file; the default scene's path, where no such file is (hexray run outside its
/// repository), gives the copy built into the binary: the same bytes, so the same SHA-1, and
/// renders and resumes as the file would.
pub(crate) fn load_scene(path: &Path) -> std::result::Result<Scene, hexray::scene::SceneError> {
    if path == Path::new(DEFAULT_SCENE) && !path.exists() {
        eprintln!(
            "hexray: no {DEFAULT_SCENE} in this folder; rendering the copy built into hexray"
        );
        return Scene::from_json(DEFAULT_SCENE_JSON, path);
    }
    Scene::load(path)
}

/// The merge radius a command line asks for, or an error for the user (exit 2): `--radius` and
/// `--alpha` only with a merging method, and sppm needs a radius above 0.
pub(crate) fn merge_radius_of(
    method: Method,
    radius: Option<f32>,
    alpha: Option<f32>,
    reach: Option<f32>,
    light_paths: Option<u32>,
    flat: &FlatScene,
    camera: &Camera,
) -> std::result::Result<hexray::transport::merging::MergeRadius, String> {
    if !method.merges() && (radius.is_some() || alpha.is_some()) {
        return Err(format!(
            "--radius is for --method {} and --alpha for {}, not {method}",
            Method::names_where(Method::merges),
            Method::names_where(Method::progressive)
        ));
    }
    if !method.progressive() && alpha.is_some() {
        return Err(format!(
            "--alpha is for the progressive methods ({}); {method}'s radius is fixed",
            Method::names_where(Method::progressive)
        ));
    }
    if !method.splats() && light_paths.is_some() {
        return Err(format!(
            "--light-paths is for the methods that trace light subpaths ({}), not {method}",
            Method::names_where(Method::splats)
        ));
    }
    let mut r = hexray::transport::merging::MergeRadius::default_for(flat, camera, method);
    if let Some(v) = radius {
        // A radius given (or resumed) is r_1 at the reach resumed, everywhere if none.
        r.initial = v;
        r.reach = reach.unwrap_or(0.0);
    }
    if let Some(a) = alpha {
        r.alpha = a;
    }
    r.light_paths = light_paths;
    if matches!(method, Method::Sppm | Method::PhotonMap) && r.initial <= 0.0 {
        return Err(format!("--method {method} needs a merge radius above 0"));
    }
    Ok(r)
}

/// Exit status when more than [`DROPPED_SHARE_LIMIT`] of the samples were dropped (not finite):
/// the image is written, but it is missing light.
pub(crate) const EXIT_DROPPED: u8 = 3;

/// The share of dropped samples above which a render exits with [`EXIT_DROPPED`].
pub(crate) const DROPPED_SHARE_LIMIT: f64 = 0.01;

/// Reads the film of `--resume NAME.exr` and takes the settings it was made with into `args`;
/// refuses a film whose EXR is from another render. The sample counts of the two may differ:
/// a render stopped without warning (SIGKILL, power) between writing its EXR and its film
/// leaves the pair one checkpoint apart, and the film, which holds the samples, is the truth.
pub(crate) fn resume_from(exr: &Path, args: &mut RenderArgs) -> Result<(Film, FilmIdentity)> {
    let path = film_file::film_path(exr);
    let (film, id) = film_file::read(&path)
        .with_context(|| format!("no film to resume beside {}", exr.display()))?;
    if exr.exists() {
        let meta = output::read_exr_metadata(exr)?;
        if meta.get("spp") != Some(id.spp.to_string().as_str()) {
            eprintln!(
                "hexray: note: {} holds {} spp and {} holds {}: resuming from the film (a render \
                 stopped between writing the two)",
                exr.display(),
                meta.get("spp").unwrap_or("no count of"),
                path.display(),
                id.spp
            );
        }
        let ours = [
            ("seed", id.seed.to_string()),
            ("method", id.method.clone()),
            ("scene_sha1", id.scene_sha1.clone()),
        ];
        for (key, value) in ours {
            if meta.get(key) != Some(value.as_str()) {
                anyhow::bail!(
                    "{} and {} come from different renders ({key} {} against {value}); \
                     resume from the pair written together",
                    exr.display(),
                    path.display(),
                    meta.get(key).unwrap_or("missing"),
                );
            }
        }
    }
    args.seed = id.seed;
    args.sampler = id.sampler;
    args.adaptive = id.adaptive;
    args.width = id.width;
    args.height = id.height;
    args.method = Some(
        Method::from_str(&id.method, true)
            .map_err(|e| anyhow::anyhow!("{}: method {}: {e}", path.display(), id.method))?,
    );
    args.light_samples = id.light_samples;
    args.radius = id.merge_radius;
    args.reach = id.merge_reach;
    // A fixed radius (photon-map) has no schedule to resume.
    args.alpha = id
        .merge_alpha
        .filter(|_| args.method.is_some_and(Method::progressive));
    args.light_paths = id.light_paths;
    args.patch_size = id.patch_size;
    args.patch_rays = id.patch_rays;
    args.scene.get_or_insert_with(|| PathBuf::from(&id.scene));
    args.out.get_or_insert_with(|| exr.to_path_buf());
    Ok((film, id))
}

/// How a step of `render` ends the command before its end: with an exit status (its message
/// printed), or with an error for `run` to report.
enum Stop {
    Exit(ExitCode),
    Error(anyhow::Error),
}

impl From<anyhow::Error> for Stop {
    fn from(e: anyhow::Error) -> Self {
        Stop::Error(e)
    }
}

type Step<T> = std::result::Result<T, Stop>;

/// A refusal of the input before any work: `error: …` on stderr, exit status 2.
fn refuse(message: impl std::fmt::Display) -> Stop {
    eprintln!("error: {message}");
    Stop::Exit(ExitCode::from(EXIT_BAD_INPUT))
}

/// `hexray render`: every check of the input before any work (a refusal exits 2 and writes
/// nothing), then the progressive render, its outputs and its summary.
pub(crate) fn render(args: &RenderArgs) -> Result<ExitCode> {
    // First, so that a stop during the set-up (a GPU kernel's compilation takes seconds) ends
    // the render before its first sample, writing nothing.
    let stop = StopRequest::install().context("installing the signal handlers")?;
    match render_steps(args, &stop) {
        Ok(code) | Err(Stop::Exit(code)) => Ok(code),
        Err(Stop::Error(e)) => Err(e),
    }
}

fn render_steps(args: &RenderArgs, stop: &StopRequest) -> Step<ExitCode> {
    let (args, resumed) = resume_settings(args)?;
    let args = &args;
    let method = args.method.unwrap_or(Method::DEFAULT);
    let scene_path = args.scene_path();
    let scene = checked_scene(&scene_path, method)?;
    let before = resumed.as_ref().map_or(0, |(f, _)| f.spp());
    if let Some((_, id)) = &resumed {
        check_resume(args, id, &scene, &scene_path, before)?;
    }
    let out = output_path(args, &scene_path)?;
    check_light_samples(args, method)?;
    check_adaptive(args, method)?;
    let budget = budget_of(args, method, before);
    check_memory(args, method)?;

    let acquired = std::time::Instant::now();
    let gpu = choose_gpu(args)?;
    if gpu.is_some() && !args.quiet {
        eprintln!(
            "hexray: adapter and device in {:.2} s",
            acquired.elapsed().as_secs_f64()
        );
    }
    // The BVH for the backend that will traverse it.
    let traversal = match gpu {
        Some(_) => gpu::GpuRenderer::TRAVERSAL,
        None => CpuBackend::TRAVERSAL,
    };
    let flat = FlatScene::build(&scene, traversal);
    let camera = Camera::new(&scene.desc.camera, args.width, args.height);
    let radius = merge_radius_of(
        method,
        args.radius,
        args.alpha,
        args.reach,
        args.light_paths,
        &flat,
        &camera,
    )
    .map_err(refuse)?;
    let radiosity = radiosity_settings_of(args, method, &flat)?;
    // The last check before any work: the outputs can be written (not found after the render).
    output::check_writable(&out, args.variance)
        .map_err(|e| refuse(format!("--out {}: {e:#}", out.display())))?;
    // Without --radius, a hardware GPU merges within a share of the default
    // (`merging::HARDWARE_GPU_RADIUS_SCALE`): its renders run many more iterations. photon-map's
    // radius, whose bias no number of iterations removes, is the same on every backend.
    let radius = match &gpu {
        Some(g) if args.radius.is_none() && method.progressive() => {
            gpu::context::default_merge_radius(&g.info, radius)
        }
        _ => radius,
    };
    let mut backend: Box<dyn Backend + '_> = match &gpu {
        None => {
            let threads = args.threads.map_or_else(
                || std::thread::available_parallelism().map_or(1, |n| n.get()),
                |t| t as usize,
            );
            let mut cpu = CpuBackend::new(&flat, camera, args.seed, threads)?;
            cpu.light_samples = args.light_samples;
            cpu.method = method;
            cpu.radius = Some(radius);
            cpu.radiosity = radiosity;
            Box::new(cpu)
        }
        Some(g) => Box::new(gpu_backend(
            args, g, &flat, camera, method, radius, radiosity,
        )?),
    };
    if !args.quiet {
        log_scene(&scene, &scene_path, &flat, args, backend.as_ref());
    }

    let record = Record {
        args,
        method,
        radius,
        radiosity,
        scene: &scene,
        scene_path: &scene_path,
        earlier_seconds: resumed.as_ref().map_or(0.0, |(_, id)| id.render_seconds),
        backend: backend.name(),
        device: backend.device(),
    };
    let mut film = match resumed {
        Some((film, _)) => film,
        None => Film::new(args.width, args.height).with_sampler(args.sampler),
    };
    let report = render_with_checkpoints(backend.as_mut(), &mut film, budget, stop, &record, &out);

    // A render that took no new samples writes nothing: earlier files stay as they were.
    if film.spp() == before {
        eprintln!("hexray: no samples were taken; nothing written");
        return Ok(match report.reason {
            StopReason::Interrupted => ExitCode::from(stop.exit_status()),
            StopReason::Failed(e) => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
            _ => ExitCode::SUCCESS,
        });
    }
    let (mut meta, id) = record.of(&film, report.seconds);
    let provenance = backend.provenance();
    for (key, value) in &provenance {
        meta.set(key, value);
    }
    write_outputs(&out, &film, &meta, &id, args)?;

    let dropped_share = warn_dropped(&film);
    // The safety net: an image nearly black where the scene's light reaches the camera.
    if let Some(w) = dark_image_warning(&flat, &camera, method, film.image_mean().0) {
        eprintln!("hexray: warning: {w}");
    }
    if !args.quiet {
        summarise(
            args,
            method,
            radius,
            &film,
            before,
            &report,
            &provenance,
            &out,
        );
    }
    Ok(match report.reason {
        StopReason::Interrupted => ExitCode::from(stop.exit_status()),
        StopReason::Failed(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
        _ if dropped_share > DROPPED_SHARE_LIMIT => ExitCode::from(EXIT_DROPPED),
        _ => ExitCode::SUCCESS,
    })
}

/// --resume: the film so far, and the settings it was made with taken into the arguments.
fn resume_settings(args: &RenderArgs) -> Step<(RenderArgs, Option<(Film, FilmIdentity)>)> {
    let mut args = args.clone();
    let resumed = match args.resume.clone() {
        None => None,
        Some(exr) => Some(
            resume_from(&exr, &mut args)
                .map_err(|e| refuse(format!("--resume {}: {e:#}", exr.display())))?,
        ),
    };
    Ok((args, resumed))
}

/// The scene file, parsed and validated (everything that can be wrong with the input is found
/// here, before any output exists), with a warning where it reaches past the tested precision.
fn checked_scene(scene_path: &Path, method: Method) -> Step<Scene> {
    let scene = load_scene(scene_path).map_err(refuse)?;
    if method.splats() {
        hexray::scene::validate::check_splat_range(&scene.desc, &method.to_string())
            .map_err(|issue| refuse(scene.error_at(issue)))?;
    }
    let extent = hexray::scene::validate::extent(&scene.desc);
    if extent > hexray::scene::validate::TESTED_COORDINATE {
        eprintln!(
            "hexray: warning: {} reaches {extent:e} from the origin; the renderer's 32-bit \
             precision is tested to {:e} (docs/stability.md)",
            scene_path.display(),
            hexray::scene::validate::TESTED_COORDINATE
        );
    }
    Ok(scene)
}

/// A resumed render continues the same scene, to a total sample count above what it has (or
/// for --time more seconds).
fn check_resume(
    args: &RenderArgs,
    id: &FilmIdentity,
    scene: &Scene,
    scene_path: &Path,
    before: u64,
) -> Step<()> {
    if id.scene_sha1 != scene.sha1 {
        return Err(refuse(format!(
            "--resume: {} has changed since the render (SHA-1 {} then, {} now); \
             a resumed render must continue the same scene",
            scene_path.display(),
            id.scene_sha1,
            scene.sha1
        )));
    }
    match (args.spp, args.time) {
        (None, None) => Err(refuse(format!(
            "--resume needs --spp (the total to reach; it has {before}) or --time \
             (seconds more)"
        ))),
        (Some(n), _) if u64::from(n) < before => Err(refuse(format!(
            "--resume: the render already has {before} samples per pixel, more \
             than --spp {n} (the total, not the samples to add)"
        ))),
        (Some(n), _) if u64::from(n) == before => {
            eprintln!("hexray: the render already has {before} samples per pixel; nothing to do");
            Err(Stop::Exit(ExitCode::SUCCESS))
        }
        _ => Ok(()),
    }
}

/// The EXR to write: --out, or out/STEM.exr after the scene file. The default is named after
/// the file's stem (no folder in it), not the scene's `name`, so that a copied scene does not
/// overwrite the original's render and no name can lead out of out/.
fn output_path(args: &RenderArgs, scene_path: &Path) -> Step<PathBuf> {
    let out = args.out.clone().unwrap_or_else(|| {
        let stem = scene_path
            .file_stem()
            .map_or("render".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from("out").join(format!("{stem}.exr"))
    });
    if out
        .extension()
        .is_none_or(|e| !e.eq_ignore_ascii_case("exr"))
    {
        return Err(refuse(format!(
            "--out {}: the output must be an .exr path (the PNG is written beside it)",
            out.display()
        )));
    }
    Ok(out)
}

/// Radiosity's settings: --patch-size and --patch-rays only with --method radiosity, and a
/// scene whose patches at that size fit the CPU's form-factor matrix (the GPU's binding is
/// checked with its limits, `gpu_backend`).
fn radiosity_settings_of(
    args: &RenderArgs,
    method: Method,
    flat: &FlatScene,
) -> Step<hexray::transport::patches::RadiositySettings> {
    use hexray::transport::patches::{
        check_count, RadiositySettings, CPU_LIMIT_REASON, MAX_PATCHES,
    };
    if method != Method::Radiosity {
        if args.patch_size.is_some() || args.patch_rays.is_some() {
            return Err(refuse(format!(
                "--patch-size and --patch-rays are for --method radiosity, not {method}"
            )));
        }
        return Ok(RadiositySettings::default());
    }
    let mut settings = RadiositySettings::default();
    if let Some(size) = args.patch_size {
        settings.patch_size = size;
    }
    if let Some(rays) = args.patch_rays {
        settings.patch_rays = rays;
    }
    let n = check_count(
        flat,
        settings.patch_size,
        MAX_PATCHES as u64,
        CPU_LIMIT_REASON,
    )
    .map_err(|e| refuse(format!("--patch-size {}: {e}", settings.patch_size)))?;
    if n == 0 {
        return Err(refuse(
            "--method radiosity: the scene has no diffuse surface to cut into patches",
        ));
    }
    Ok(settings)
}

/// --adaptive is path tracing's alone.
fn check_adaptive(args: &RenderArgs, method: Method) -> Step<()> {
    if args.adaptive && method != Method::Path {
        let given = if args.method.is_none() {
            " (the default method; add --method path)"
        } else {
            ""
        };
        return Err(refuse(format!(
            "--adaptive is for --method path; {method}{given} spends the same samples on \
             every pixel"
        )));
    }
    Ok(())
}

/// --light-samples above 1 is path tracing's alone.
fn check_light_samples(args: &RenderArgs, method: Method) -> Step<()> {
    if args.light_samples > 1 && method != Method::Path {
        let given = if args.method.is_none() {
            " (the default method; add --method path)"
        } else {
            ""
        };
        return Err(refuse(format!(
            "--light-samples {} is for --method path; {method}{given} takes one light \
             sample per vertex",
            args.light_samples
        )));
    }
    Ok(())
}

/// When to stop. --spp is the total: a resumed render adds what is missing.
fn budget_of(args: &RenderArgs, method: Method, before: u64) -> Budget {
    Budget {
        spp: match (args.spp, args.time, args.target_error) {
            (Some(n), _, _) => Some(n - before as u32),
            (None, None, None) => Some(method.default_samples()),
            _ => None,
        },
        seconds: args.time,
        relmse: args.target_error,
    }
}

/// The host memory the render will hold, against what the machine has free, before any of it
/// is allocated.
fn check_memory(args: &RenderArgs, method: Method) -> Step<()> {
    let pixels = u64::from(args.width) * u64::from(args.height);
    let needed = pixels * hexray::render::host_bytes_per_pixel(method);
    match hexray::render::available_memory() {
        Some(free) if needed > free => Err(refuse(format!(
            "a {}x{} render with {method} needs about {:.1} GiB of memory and {:.1} GiB \
             is available; render a smaller image (--width, --height)",
            args.width,
            args.height,
            needed as f64 / (1u64 << 30) as f64,
            free as f64 / (1u64 << 30) as f64
        ))),
        _ => Ok(()),
    }
}

/// The GPU adapter of --backend, or None for the CPU backend. A software adapter (lavapipe)
/// runs the kernel on the very cores the CPU backend uses, and slower, so `auto` takes it only
/// when asked for by --adapter.
fn choose_gpu(args: &RenderArgs) -> Step<Option<gpu::Gpu>> {
    Ok(match args.backend {
        BackendChoice::Cpu => None,
        BackendChoice::Gpu => Some(
            gpu::acquire(args.adapter.as_deref())
                .map_err(|e| refuse(format!("--backend gpu: {e}")))?,
        ),
        BackendChoice::Auto => match gpu::acquire(args.adapter.as_deref()) {
            Ok(g) if g.info.device_type == wgpu::DeviceType::Cpu && args.adapter.is_none() => {
                if !args.quiet {
                    eprintln!(
                        "hexray: backend cpu (auto): the only GPU adapter is {}, a software \
                         rasteriser on these same cores and slower than the CPU backend \
                         (--backend gpu uses it anyway)",
                        g.info.name
                    );
                }
                None
            }
            Ok(g) => {
                if !args.quiet {
                    eprintln!(
                        "hexray: backend gpu (auto): found {}",
                        gpu::context::describe(&g.info)
                    );
                }
                Some(g)
            }
            Err(e) => {
                if !args.quiet {
                    eprintln!("hexray: backend cpu (auto): {e}");
                }
                None
            }
        },
    })
}

/// The GPU backend on adapter `g`: the scene and image checked against its limits, then the
/// kernel built.
fn gpu_backend(
    args: &RenderArgs,
    g: &gpu::Gpu,
    flat: &FlatScene,
    camera: Camera,
    method: Method,
    radius: hexray::transport::merging::MergeRadius,
    radiosity: hexray::transport::patches::RadiositySettings,
) -> Step<hexray::render::GpuBackend> {
    let checks = if args.shader_checks {
        gpu::Checks::Checked
    } else {
        gpu::Checks::Unchecked
    };
    let residency = match args.scene_residency {
        Some(ResidencyChoice::Storage) => gpu::Residency::Storage,
        Some(ResidencyChoice::Uniform) => gpu::Residency::Uniform,
        None => gpu::Residency::preferred(&g.info, &g.device.limits(), flat),
    };
    let limits = g.device.limits();
    gpu::limits::check_scene_fits(&limits, residency, flat)
        .and_then(|_| gpu::limits::check_image_fits(&limits, method, args.width, args.height))
        .map_err(|e| refuse(format!("--backend gpu: {e}")))?;
    if method == Method::Radiosity {
        gpu::radiosity::check_patches_fit(&limits, flat, radiosity).map_err(|e| {
            refuse(format!(
                "--backend gpu, --patch-size {}: {e}",
                radiosity.patch_size
            ))
        })?;
    }
    let compile = std::time::Instant::now();
    let cache = gpu::pipeline_cache::cache_dir()
        .and_then(|dir| gpu::pipeline_cache::open(&g.device, &g.info, &dir));
    let mut renderer = gpu::GpuRenderer::new(
        &g.device,
        &g.queue,
        flat,
        camera,
        args.seed,
        hexray::transport::faults::Faults::NONE,
        checks,
        residency,
        method,
        hexray::cpu::shadow_probe::shadow_threshold_for(method, flat, &camera),
        cache.as_ref().map(|c| &c.cache),
    )?;
    renderer.set_light_samples(args.light_samples);
    renderer.set_merge_radius(radius);
    renderer.set_radiosity(radiosity);
    let built = compile.elapsed().as_secs_f64();
    let cached = cache
        .as_ref()
        .map(|c| (c.loaded_bytes, c.save(), c.path.display()));
    if !args.quiet {
        eprintln!(
            "hexray: kernel built in {built:.2} s ({residency:?} residency, {checks:?}; a driver may JIT it at the first pass)"
        );
        match cached {
            Some((read, Ok(written), path)) => {
                eprintln!("hexray: pipeline cache {path}: {read} bytes read, {written} written")
            }
            Some((_, Err(e), path)) => {
                eprintln!("hexray: warning: pipeline cache {path} not written: {e}")
            }
            None => {
                eprintln!("hexray: pipeline cache: none (the adapter offers none, or it is off)")
            }
        }
    }
    Ok(hexray::render::GpuBackend {
        renderer,
        adapter: gpu::context::describe(&g.info),
    })
}

/// What is rendered, where, and how long its BVH took.
fn log_scene(
    scene: &Scene,
    scene_path: &Path,
    flat: &FlatScene,
    args: &RenderArgs,
    backend: &dyn Backend,
) {
    eprintln!(
        "hexray: {} ({} triangles, {} spheres, {} emitters, {} BVH nodes) at {}x{} on {} ({})",
        scene_path.display(),
        flat.triangles.len(),
        flat.spheres.len(),
        flat.emitters.len(),
        flat.nodes.len(),
        args.width,
        args.height,
        backend.name(),
        backend.device()
    );
    eprintln!(
        "hexray: BVH of {} primitives built in {:.3} s",
        flat.triangles.len() + flat.spheres.len(),
        flat.bvh_seconds
    );
    for line in mesh_lines(scene) {
        eprintln!("hexray: {line}");
    }
}

/// What every output of a render records: the settings, the scene, and the time of all its
/// sessions (a resumed render adds to the time before).
struct Record<'a> {
    args: &'a RenderArgs,
    method: Method,
    radius: hexray::transport::merging::MergeRadius,
    /// Radiosity's patch size and rays (recorded only for --method radiosity).
    radiosity: hexray::transport::patches::RadiositySettings,
    scene: &'a Scene,
    scene_path: &'a Path,
    earlier_seconds: f64,
    backend: &'static str,
    device: String,
}

impl Record<'_> {
    /// The EXR metadata and the film's identity of `film` after `seconds` of this session.
    fn of(&self, film: &Film, seconds: f64) -> (Metadata, FilmIdentity) {
        let (args, method) = (self.args, self.method);
        let mut meta = Metadata::default();
        meta.set("spp", film.spp());
        meta.set("seed", args.seed);
        meta.set("sampler", args.sampler);
        if args.adaptive {
            meta.set("adaptive", "true");
        }
        meta.set("light_samples", args.light_samples);
        meta.set("method", method);
        meta.set("backend", self.backend);
        meta.set("device", &self.device);
        meta.set(
            "render_seconds",
            format!("{:.6}", self.earlier_seconds + seconds),
        );
        meta.set("scene", self.scene_path.display());
        meta.set("scene_name", &self.scene.desc.name);
        meta.set("scene_sha1", &self.scene.sha1);
        meta.set("hexray_version", env!("CARGO_PKG_VERSION"));
        meta.set("dropped_samples", film.dropped());
        meta.set("width", args.width);
        meta.set("height", args.height);
        if let Some(omitted) = method.omits() {
            meta.set("omits", omitted);
        }
        if let Some(target) = args.target_error {
            meta.set("target_error", format!("{target:e}"));
            if let Some(e) = film.estimated_relmse() {
                meta.set("estimated_relmse", format!("{e:e}"));
            }
        }
        let merges = method.merges();
        let id = FilmIdentity {
            version: FilmIdentity::VERSION,
            width: args.width,
            height: args.height,
            spp: film.spp(),
            adaptive: args.adaptive,
            seed: args.seed,
            sampler: args.sampler,
            method: method.to_string(),
            light_samples: args.light_samples,
            merge_radius: merges.then_some(self.radius.initial),
            merge_reach: (merges && self.radius.reach > 0.0).then_some(self.radius.reach),
            merge_alpha: merges.then_some(self.radius.alpha),
            light_paths: self.radius.light_paths,
            patch_size: (method == Method::Radiosity).then_some(self.radiosity.patch_size),
            patch_rays: (method == Method::Radiosity).then_some(self.radiosity.patch_rays),
            scene: self.scene_path.display().to_string(),
            scene_sha1: self.scene.sha1.clone(),
            render_seconds: self.earlier_seconds + seconds,
        };
        (meta, id)
    }
}

/// The progressive render with its progress line and, with --checkpoint, the outputs so far
/// written atomically every so often, so that a kill loses at most the interval.
fn render_with_checkpoints(
    backend: &mut dyn Backend,
    film: &mut Film,
    budget: Budget,
    stop: &StopRequest,
    record: &Record,
    out: &Path,
) -> hexray::render::RenderReport {
    let args = record.args;
    let before = film.spp();
    let pixels = u64::from(args.width) * u64::from(args.height);
    let mut progress = Progress::new(args.quiet, budget, before, pixels);
    let mut last_checkpoint = 0.0;
    let on_pass = |film: &Film, spp, secs| {
        let estimate = budget.relmse.and_then(|_| film.estimated_relmse());
        progress.update(spp, secs, estimate);
        if args
            .checkpoint
            .is_some_and(|every| secs - last_checkpoint >= every)
        {
            last_checkpoint = secs;
            let (meta, id) = record.of(film, secs);
            if let Err(e) = write_outputs(out, film, &meta, &id, args) {
                progress.println(&format!("hexray: warning: checkpoint not written: {e:#}"));
            }
        }
    };
    let report = if args.adaptive {
        let settings = AdaptiveSettings::default();
        render_adaptive(backend, film, budget, settings, stop.flag(), on_pass)
    } else {
        render_progressive(backend, film, budget, stop.flag(), on_pass)
    };
    progress.finish();
    report
}

/// Never silent: a dropped sample (not finite) is light missing from the image. Returns the
/// share of samples dropped.
fn warn_dropped(film: &Film) -> f64 {
    let taken = film.spp() * u64::from(film.width) * u64::from(film.height);
    let dropped = film.dropped();
    let dropped_share = dropped as f64 / taken as f64;
    if dropped > 0 {
        eprintln!(
            "hexray: warning: dropped {dropped} of {taken} samples ({:.3} %) whose value was not \
             finite{}",
            100.0 * dropped_share,
            if dropped_share > DROPPED_SHARE_LIMIT {
                format!(
                    "; above {} %, so the exit status is {EXIT_DROPPED}",
                    100.0 * DROPPED_SHARE_LIMIT
                )
            } else {
                String::new()
            }
        );
    }
    dropped_share
}

/// The summary on stderr: samples, time, camera paths/s and why the render stopped; the image
/// mean with its standard error; for a consistent method, the bias it leaves; the method's
/// provenance; the files written.
#[allow(clippy::too_many_arguments)]
fn summarise(
    args: &RenderArgs,
    method: Method,
    radius: hexray::transport::merging::MergeRadius,
    film: &Film,
    before: u64,
    report: &hexray::render::RenderReport,
    provenance: &[(&'static str, String)],
    out: &Path,
) {
    let pixels = u64::from(args.width) * u64::from(args.height);
    let (mean, se) = film.image_mean();
    let paths = (film.spp() - before) as f64 * pixels as f64;
    let why = match &report.reason {
        StopReason::SampleCount => "sample count reached",
        StopReason::TimeBudget => "time budget reached",
        StopReason::ErrorTarget => "error target reached",
        StopReason::Interrupted => "interrupted; samples so far kept",
        StopReason::Failed(_) => "the backend failed; samples so far kept",
    };
    let resumed_from = if before > 0 {
        format!(" (resumed from {before})")
    } else {
        String::new()
    };
    eprintln!(
        "rendered {} spp{resumed_from} with {} in {:.2} s ({:.3} M camera paths/s; {why}); \
         dropped {} samples",
        film.spp(),
        method,
        report.seconds,
        paths / report.seconds / 1e6,
        film.dropped(),
    );
    if let Some(first) = report.first_pass {
        // The passes after the first: their samples per pixel, camera paths and seconds.
        let rest = report.seconds - first.seconds;
        let rest_spp = (film.spp() - before) as f64 - first.spp;
        let rate = if rest > 0.0 && rest_spp > 0.0 {
            format!(
                "; the other {rest_spp:.0} spp at {:.3} M camera paths/s",
                (paths - first.spp * pixels as f64) / rest / 1e6
            )
        } else {
            String::new()
        };
        eprintln!(
            "first pass {:.0} spp in {:.3} s (start-up included, such as a GPU driver \
             compiling the kernel at its first dispatch){rate}",
            first.spp, first.seconds
        );
    }
    eprintln!(
        "image mean RGB {:.4} {:.4} {:.4} (s.e. {:.1e} {:.1e} {:.1e})",
        mean[0], mean[1], mean[2], se[0], se[1], se[2]
    );
    if method == Method::PhotonMap {
        eprintln!(
            "photon-map is biased: its density estimates within r = {:e} blur the light, a bias \
             that does not shrink with samples (the radius is fixed) and that the standard error \
             does not cover",
            radius.initial
        );
    } else if method.merges() {
        eprintln!(
            "{} is consistent, not unbiased: merging within {}r = {:e} shrinking to {:e} \
             (alpha {}) leaves a bias that the standard error does not cover",
            method,
            if radius.reach > 0.0 { "at most " } else { "" },
            radius.initial,
            radius.at((film.spp() as u32).saturating_sub(1)),
            radius.alpha
        );
    }
    if let Some(omitted) = method.omits() {
        eprintln!(
            "{method} is biased: it leaves out {omitted}; the standard error covers its noise only"
        );
    }
    if let Some(target) = args.target_error {
        let estimate = film.estimated_relmse().unwrap_or(f64::NAN);
        eprintln!(
            "estimated relMSE {estimate:.3e} (target {target:e}), from the pixels' variances{}",
            if method.merges() || method.omits().is_some() {
                "; the method's bias is not in it"
            } else {
                ""
            }
        );
    }
    for (key, value) in provenance {
        eprintln!("{key}: {value}");
    }
    let (exr, png, var) = output::output_paths(out);
    eprintln!(
        "wrote {}, {} and {}",
        exr.display(),
        png.display(),
        film_file::film_path(&exr).display()
    );
    if args.variance {
        if film.spp() >= 2 {
            eprintln!("wrote {}", var.display());
        } else {
            eprintln!(
                "no variance written: one sample per pixel has no sample variance \
                 ({} left as it was)",
                var.display()
            );
        }
    }
}

/// The progress of a render on stderr: a bar on a terminal; elsewhere (batch logs) a plain line
/// every [`Progress::LOG_EVERY`] seconds. Both give samples, the rate, elapsed time and what
/// is left (an ETA for a sample count, the remaining time for --time).
pub(crate) struct Progress {
    bar: Option<indicatif::ProgressBar>,
    log: bool,
    last_log: f64,
    budget: Budget,
    before: u64,
    pixels: u64,
}

impl Progress {
    const LOG_EVERY: f64 = 10.0;

    fn new(quiet: bool, budget: Budget, before: u64, pixels: u64) -> Progress {
        let terminal = std::io::stderr().is_terminal();
        let bar = (!quiet && terminal).then(|| {
            let bar = indicatif::ProgressBar::new(1000);
            bar.set_style(
                indicatif::ProgressStyle::with_template("{bar:40} {msg}")
                    .expect("a valid template"),
            );
            bar
        });
        Progress {
            bar,
            log: !quiet && !terminal,
            last_log: 0.0,
            budget,
            before,
            pixels,
        }
    }

    /// The progress line and the share done, from the samples and seconds so far and, with an
    /// error target, the estimated relMSE (which falls as 1 / samples).
    fn line(&self, spp: u32, secs: f64, estimate: Option<f64>) -> (String, f64) {
        let new = spp as f64 - self.before as f64;
        let rate = new * self.pixels as f64 / secs / 1e6;
        let mut fraction = 0.0f64;
        let mut left = f64::INFINITY;
        let mut error = String::new();
        if let (Some(target), Some(e)) = (self.budget.relmse, estimate) {
            fraction = (target / e).min(1.0);
            left = secs * (e / target - 1.0).max(0.0);
            error = format!(", relMSE {e:.2e} of {target:.0e}");
        }
        if let Some(n) = self.budget.spp {
            let target = self.before as f64 + n as f64;
            fraction = fraction.max(new / n as f64);
            left = left.min((target - spp as f64) * secs / new.max(1.0));
        }
        if let Some(t) = self.budget.seconds {
            fraction = fraction.max(secs / t);
            left = left.min((t - secs).max(0.0));
        }
        let target = self
            .budget
            .spp
            .map_or(String::new(), |n| format!("/{}", self.before + n as u64));
        (
            format!(
                "{spp}{target} spp{error}, {rate:.3} M camera paths/s, {} elapsed, {} left",
                clock(secs),
                clock(left)
            ),
            fraction.clamp(0.0, 1.0),
        )
    }

    fn update(&mut self, spp: u32, secs: f64, estimate: Option<f64>) {
        if let Some(bar) = &self.bar {
            let (msg, fraction) = self.line(spp, secs, estimate);
            bar.set_position((fraction * 1000.0) as u64);
            bar.set_message(msg);
        } else if self.log && secs - self.last_log >= Self::LOG_EVERY {
            self.last_log = secs;
            eprintln!("hexray: {}", self.line(spp, secs, estimate).0);
        }
    }

    fn println(&self, text: &str) {
        match &self.bar {
            Some(bar) => bar.println(text),
            None => eprintln!("{text}"),
        }
    }

    fn finish(self) {
        if let Some(bar) = self.bar {
            bar.finish_and_clear();
        }
    }
}

/// Seconds as h:mm:ss (or m:ss), "?" when unknown.
pub(crate) fn clock(secs: f64) -> String {
    if !secs.is_finite() {
        return "?".into();
    }
    let s = secs.round() as u64;
    if s >= 3600 {
        format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
    } else {
        format!("{}:{:02}", s / 60, s % 60)
    }
}

/// Writes the render's EXR, PNG and film (and its variance with --variance, where there are
/// two samples or more to estimate it from), each atomically.
pub(crate) fn write_outputs(
    out: &Path,
    film: &Film,
    meta: &Metadata,
    id: &FilmIdentity,
    args: &RenderArgs,
) -> Result<()> {
    let (exr, png, var) = output::output_paths(out);
    let image = RgbImage {
        width: film.width as usize,
        height: film.height as usize,
        pixels: film.mean_image(),
    };
    output::write_exr(&exr, &image, meta)?;
    output::write_png(&png, &image, args.exposure)?;
    film_file::write(&film_file::film_path(&exr), film, id)?;
    if args.variance && film.spp() >= 2 {
        let v = RgbImage {
            pixels: film.variance_image(),
            ..image
        };
        let mut vmeta = meta.clone();
        vmeta.set("content", "variance of the pixel mean");
        output::write_exr(&var, &v, &vmeta)?;
    }
    Ok(())
}
