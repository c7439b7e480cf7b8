//! One way to render in a test, on either backend: the [`Render`] builder, with named options
//! and the defaults below, and [`on_each_backend!`], which runs one test body on each backend.
//!
//! ```ignore
//! let film = Render::file("scenes/cornell_box.json").size(64, 64).spp(16).seed(3).on(backend);
//! ```

use super::repo;
use hexray::cpu::shadow_probe::shadow_threshold_for;
use hexray::cpu::{
    render_iterations, render_pass, render_radiosity_pass, render_whitted_pass, LightPassBuffers,
};
use hexray::film::Film;
use hexray::gpu::{Checks, GpuRenderer, Residency};
use hexray::layout::FlatScene;
use hexray::math::sampling::SamplerKind;
use hexray::scene::Scene;
use hexray::transport::camera::Camera;
use hexray::transport::faults::Faults;
use hexray::transport::merging::MergeRadius;
use hexray::transport::method::Method;
use hexray::transport::patches::{Patches, RadiositySettings};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// The backend a test body runs on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    Cpu,
    Gpu,
}

impl std::fmt::Display for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Backend::Cpu => "CPU",
            Backend::Gpu => "GPU",
        })
    }
}

/// What is rendered: a scene file, or a loaded (possibly changed) scene.
#[derive(Clone, Copy)]
enum Source<'a> {
    File(&'a str),
    Scene(&'a Scene),
}

/// A render of a scene, seen by its camera. Defaults: 32x32, 1 sample (or iteration), seed 0,
/// path tracing, one shadow ray per diffuse vertex, no planted fault, the scene's default merge
/// radius schedule, the independent sampler. The CPU renders on all cores; the GPU with the
/// kernel and residency the CLI uses and no runtime checks.
#[derive(Clone, Copy)]
pub struct Render<'a> {
    source: Source<'a>,
    width: u32,
    height: u32,
    spp: u32,
    seed: u32,
    method: Method,
    light_samples: u32,
    faults: Faults,
    radius: Option<MergeRadius>,
    radiosity: RadiositySettings,
    sampler: SamplerKind,
}

impl<'a> Render<'a> {
    /// A render of the scene file `rel` (a path under the repository root).
    pub fn file(rel: &'a str) -> Self {
        Self::of(Source::File(rel))
    }

    /// A render of a loaded (possibly changed, see [`super::load_changed`]) scene.
    pub fn scene(scene: &'a Scene) -> Self {
        Self::of(Source::Scene(scene))
    }

    fn of(source: Source<'a>) -> Self {
        Render {
            source,
            width: 32,
            height: 32,
            spp: 1,
            seed: 0,
            method: Method::Path,
            light_samples: 1,
            faults: Faults::NONE,
            radius: None,
            radiosity: RadiositySettings::default(),
            sampler: SamplerKind::Independent,
        }
    }

    /// The sampler that draws the film's numbers (`--sampler`).
    pub fn sampler(self, sampler: SamplerKind) -> Self {
        Render { sampler, ..self }
    }

    /// An empty film of this render's size and sampler.
    fn new_film(&self) -> Film {
        Film::new(self.width, self.height).with_sampler(self.sampler)
    }

    pub fn size(self, width: u32, height: u32) -> Self {
        Render {
            width,
            height,
            ..self
        }
    }

    /// Samples per pixel of path tracing; iterations of the methods with light subpaths.
    pub fn spp(self, spp: u32) -> Self {
        Render { spp, ..self }
    }

    pub fn seed(self, seed: u32) -> Self {
        Render { seed, ..self }
    }

    pub fn method(self, method: Method) -> Self {
        Render { method, ..self }
    }

    /// Shadow rays per diffuse vertex (path tracing).
    pub fn light_samples(self, light_samples: u32) -> Self {
        Render {
            light_samples,
            ..self
        }
    }

    pub fn faults(self, faults: Faults) -> Self {
        Render { faults, ..self }
    }

    /// The merge radius schedule of a merging method (sppm, vcm).
    pub fn radius(self, radius: MergeRadius) -> Self {
        Render {
            radius: Some(radius),
            ..self
        }
    }

    /// Radiosity's patch size and form-factor rays.
    pub fn radiosity(self, radiosity: RadiositySettings) -> Self {
        Render { radiosity, ..self }
    }

    /// Radiosity's solution on the CPU (the scene's patches at this render's settings, solved
    /// with its seed and faults).
    pub fn cpu_solution(&self) -> hexray::cpu::radiosity::Solution {
        let (_, flat) = self.loaded(Backend::Cpu);
        self.cpu_solution_of(&flat)
    }

    /// Radiosity's patch table at this render's settings (as both backends cut it).
    pub fn cpu_patches(&self) -> Patches {
        let (_, flat) = self.loaded(Backend::Cpu);
        Patches::build(&flat, self.radiosity.patch_size).unwrap()
    }

    fn cpu_solution_of(&self, flat: &FlatScene) -> hexray::cpu::radiosity::Solution {
        let patches = Patches::build(flat, self.radiosity.patch_size).unwrap();
        hexray::cpu::radiosity::solve(
            flat,
            patches,
            self.seed,
            self.radiosity.patch_rays,
            self.faults,
        )
        .0
    }

    /// The scene, and its layout flattened for `backend` (its BVH built for that backend's
    /// traversal, `FlatScene::build`).
    fn loaded(&self, backend: Backend) -> (std::borrow::Cow<'a, Scene>, FlatScene) {
        let traversal = match backend {
            Backend::Cpu => hexray::render::CpuBackend::TRAVERSAL,
            Backend::Gpu => GpuRenderer::TRAVERSAL,
        };
        let scene = self.source_scene();
        let flat = FlatScene::build(&scene, traversal);
        (scene, flat)
    }

    fn source_scene(&self) -> std::borrow::Cow<'a, Scene> {
        match self.source {
            Source::File(rel) => {
                std::borrow::Cow::Owned(Scene::load(&repo(rel)).unwrap_or_else(|e| panic!("{e}")))
            }
            Source::Scene(scene) => std::borrow::Cow::Borrowed(scene),
        }
    }

    fn camera(&self, scene: &Scene) -> Camera {
        Camera::new(&scene.desc.camera, self.width, self.height)
    }

    /// The film on `backend`.
    pub fn on(&self, backend: Backend) -> Film {
        match backend {
            Backend::Cpu => self.cpu(),
            Backend::Gpu => self.gpu(),
        }
    }

    /// The film on the CPU.
    pub fn cpu(&self) -> Film {
        let (scene, flat) = self.loaded(Backend::Cpu);
        let camera = self.camera(&scene);
        let mut film = self.new_film();
        if self.method.splats() {
            let radius = self
                .radius
                .unwrap_or_else(|| MergeRadius::default_for(&flat, &camera, self.method));
            let mut buffers = LightPassBuffers::new(&flat, &camera, self.method, radius);
            render_iterations(
                &flat,
                &camera,
                self.seed,
                0,
                self.spp,
                self.method,
                self.faults,
                &mut buffers,
                &mut film,
            );
        } else if self.method == Method::Radiosity {
            let solution = self.cpu_solution_of(&flat);
            render_radiosity_pass(
                &flat,
                &camera,
                &solution,
                self.seed,
                0,
                self.spp,
                self.faults,
                &mut film,
            );
        } else if self.method == Method::Whitted {
            render_whitted_pass(
                &flat,
                &camera,
                self.seed,
                0,
                self.spp,
                self.faults,
                &mut film,
            );
        } else {
            render_pass(
                &flat,
                &camera,
                self.seed,
                0,
                self.spp,
                self.light_samples,
                self.faults,
                &mut film,
            );
        }
        film
    }

    /// The film on the GPU (the test's [`super::gpu`], which must exist).
    pub fn gpu(&self) -> Film {
        let mut r = self.gpu_renderer();
        r.set_light_samples(self.light_samples);
        let mut film = self.new_film();
        r.render(0, self.spp, &mut film).unwrap();
        film
    }

    /// The film after `spp` samples asked of `backend` with a stop set `after` into them
    /// (`Backend::pass_until`), then the rest asked with no stop: what a stop under way leaves,
    /// and what the render goes on from. Returns the film and the samples the stopped pass kept.
    pub fn stopped_under_way(&self, backend: Backend, after: std::time::Duration) -> (Film, u32) {
        use std::sync::atomic::{AtomicBool, Ordering};
        let (_, flat) = self.loaded(backend);
        let mut target = self.backend(backend, &flat);
        let mut film = self.new_film();
        let stop = AtomicBool::new(false);
        std::thread::scope(|s| {
            s.spawn(|| {
                std::thread::sleep(after);
                stop.store(true, Ordering::SeqCst);
            });
            target.pass_until(0, self.spp, &mut film, &stop).unwrap();
        });
        let kept = film.spp() as u32;
        target.pass(kept, self.spp - kept, &mut film).unwrap();
        (film, kept)
    }

    /// The film of a progressive render (`render::render_progressive`) on `backend` that stops
    /// at the error target `relmse` (`--target-error`), or at `spp` samples, whichever first.
    pub fn until_error_target(&self, backend: Backend, relmse: f64) -> Film {
        use hexray::render::{render_progressive, Budget, StopReason};
        let (_, flat) = self.loaded(backend);
        let mut target = self.backend(backend, &flat);
        let mut film = self.new_film();
        let budget = Budget {
            spp: Some(self.spp),
            relmse: Some(relmse),
            ..Budget::default()
        };
        let never = std::sync::atomic::AtomicBool::new(false);
        let report = render_progressive(target.as_mut(), &mut film, budget, &never, |_, _, _| {});
        assert_eq!(report.reason, StopReason::ErrorTarget, "{backend:?}");
        film
    }

    /// The film of an adaptive render (`render::adaptive`, `--adaptive`) on `backend`: `spp`
    /// samples per pixel on average, spent as `settings` say.
    pub fn adaptive(
        &self,
        backend: Backend,
        settings: hexray::render::adaptive::AdaptiveSettings,
    ) -> Film {
        use hexray::render::adaptive::render_adaptive;
        use hexray::render::{Budget, StopReason};
        let (_, flat) = self.loaded(backend);
        let mut target = self.backend(backend, &flat);
        let mut film = self.new_film();
        let budget = Budget {
            spp: Some(self.spp),
            ..Budget::default()
        };
        let never = std::sync::atomic::AtomicBool::new(false);
        let report = render_adaptive(
            target.as_mut(),
            &mut film,
            budget,
            settings,
            &never,
            |_, _, _| {},
        );
        assert_eq!(report.reason, StopReason::SampleCount, "{backend:?}");
        film
    }

    /// An adaptive render on `backend` with the default settings, stopped `after` into it
    /// (`spp` should be more than that time takes): the film and why the render ended.
    pub fn adaptive_stopped(
        &self,
        backend: Backend,
        after: std::time::Duration,
    ) -> (Film, hexray::render::StopReason) {
        use hexray::render::adaptive::{render_adaptive, AdaptiveSettings};
        use std::sync::atomic::{AtomicBool, Ordering};
        let (_, flat) = self.loaded(backend);
        let mut target = self.backend(backend, &flat);
        let mut film = self.new_film();
        let budget = hexray::render::Budget {
            spp: Some(self.spp),
            ..Default::default()
        };
        let stop = AtomicBool::new(false);
        let settings = AdaptiveSettings::default();
        let report = std::thread::scope(|s| {
            s.spawn(|| {
                std::thread::sleep(after);
                stop.store(true, Ordering::SeqCst);
            });
            render_adaptive(
                target.as_mut(),
                &mut film,
                budget,
                settings,
                &stop,
                |_, _, _| {},
            )
        });
        (film, report.reason)
    }

    /// This render's scene and method as a `render::Backend` on `backend` (CPU: two threads).
    fn backend<'f>(
        &self,
        backend: Backend,
        flat: &'f FlatScene,
    ) -> Box<dyn hexray::render::Backend + 'f> {
        use hexray::render::{CpuBackend, GpuBackend};
        let camera = self.camera(&self.source_scene());
        match backend {
            Backend::Cpu => {
                let mut b = CpuBackend::new(flat, camera, self.seed, 2).unwrap();
                b.method = self.method;
                b.radius = self.radius;
                b.faults = self.faults;
                b.radiosity = self.radiosity;
                Box::new(b)
            }
            Backend::Gpu => Box::new(GpuBackend {
                renderer: self.gpu_renderer(),
                adapter: String::new(),
            }),
        }
    }

    /// A GPU renderer of the scene (with the merge radius schedule, if one is set), for tests
    /// that drive it directly.
    pub fn gpu_renderer(&self) -> GpuRenderer {
        let gpu = super::gpu().expect("a GPU test runs only where common::gpu() gives one");
        let (scene, flat) = self.loaded(Backend::Gpu);
        let camera = self.camera(&scene);
        let mut r = GpuRenderer::new(
            &gpu.device,
            &gpu.queue,
            &flat,
            camera,
            self.seed,
            self.faults,
            Checks::Unchecked,
            Residency::preferred(&gpu.info, &gpu.device.limits(), &flat),
            self.method,
            shadow_threshold_for(self.method, &flat, &camera),
            None,
        )
        .unwrap();
        if let Some(radius) = self.radius {
            r.set_merge_radius(radius);
        }
        r.set_radiosity(self.radiosity);
        r
    }

    /// The films of iterations `0..spp` of one render of a method that splats or merges (light,
    /// bdpt, sppm, vcm), each alone (iteration i with the seed's streams of iteration i and,
    /// when merging, the schedule's radius r_i), so that each is one independent estimate of
    /// every pixel: the batches of [`super::parity::parity_of_iterations`]. The GPU renders them
    /// with one renderer, asked for one iteration at a time.
    pub fn iterations_on(&self, backend: Backend) -> Vec<Film> {
        let (w, h) = (self.width, self.height);
        match backend {
            Backend::Cpu => {
                let (scene, flat) = self.loaded(Backend::Cpu);
                let camera = self.camera(&scene);
                let radius = self
                    .radius
                    .unwrap_or_else(|| MergeRadius::default_for(&flat, &camera, self.method));
                let mut buffers = LightPassBuffers::new(&flat, &camera, self.method, radius);
                (0..self.spp)
                    .map(|i| {
                        let mut film = Film::new(w, h);
                        render_iterations(
                            &flat,
                            &camera,
                            self.seed,
                            i,
                            1,
                            self.method,
                            self.faults,
                            &mut buffers,
                            &mut film,
                        );
                        film
                    })
                    .collect()
            }
            Backend::Gpu => {
                let mut r = self.gpu_renderer();
                (0..self.spp)
                    .map(|i| {
                        let mut film = Film::new(w, h);
                        r.render(i, 1, &mut film).unwrap();
                        film
                    })
                    .collect()
            }
        }
    }

    /// [`Render::cpu`] of a scene file, rendered once per test binary for each distinct render:
    /// the first test that asks renders it, the others wait for it and share the film. A render
    /// that several tests compare against (their planted faults on the other side) is rendered
    /// once.
    pub fn cpu_shared(&self) -> Arc<Film> {
        type Cache = Mutex<HashMap<String, Arc<OnceLock<Arc<Film>>>>>;
        static CACHE: OnceLock<Cache> = OnceLock::new();
        let Source::File(rel) = self.source else {
            panic!("cpu_shared renders scene files only");
        };
        let key = format!(
            "{} {}x{} {} {} {:?} {} {:?} {:?}",
            repo(rel).display(),
            self.width,
            self.height,
            self.spp,
            self.seed,
            self.method,
            self.light_samples,
            self.faults,
            self.radius
        );
        let cell = CACHE
            .get_or_init(Default::default)
            .lock()
            .unwrap()
            .entry(key)
            .or_default()
            .clone();
        cell.get_or_init(|| Arc::new(self.cpu())).clone()
    }
}

/// One test body run on each backend, as one test per backend: `name::cpu` and `name::gpu`.
/// The GPU's test returns at once (a skip) where [`super::gpu`] gives no GPU; that prints why,
/// and fails where `CI` is set.
///
/// ```ignore
/// on_each_backend! {
///     /// The property and its statistic.
///     fn furnace_albedo_0_5_converges_to_1(backend) {
///         furnace(backend, "scenes/furnace/diffuse_0_5.json");
///     }
/// }
/// ```
macro_rules! on_each_backend {
    ($($(#[$attr:meta])* fn $name:ident($backend:ident) $body:block)*) => {$(
        $(#[$attr])*
        mod $name {
            #[allow(unused_imports)]
            use super::*;

            fn body($backend: $crate::common::Backend) $body

            #[test]
            fn cpu() {
                body($crate::common::Backend::Cpu);
            }

            #[test]
            fn gpu() {
                if $crate::common::gpu().is_none() {
                    return;
                }
                body($crate::common::Backend::Gpu);
            }
        }
    )*};
}
pub(crate) use on_each_backend;
