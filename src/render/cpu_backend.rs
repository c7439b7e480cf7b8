//! The CPU backend as a [`Backend`]: path tracing in passes of tiles, the light-subpath methods
//! in iterations of a light pass and a camera pass (`crate::cpu`), on a rayon pool of its own.

use super::Backend;
use crate::film::provenance::{bidirectional_provenance, merging_provenance};
use crate::film::{check_film_for, Film};
use std::sync::atomic::AtomicBool;

/// The CPU backend as a [`Backend`], on a rayon pool of its own.
pub struct CpuBackend<'a> {
    pub scene: &'a crate::layout::FlatScene,
    pub camera: crate::transport::camera::Camera,
    pub seed: u32,
    pub faults: crate::transport::faults::Faults,
    /// Shadow rays per diffuse vertex (`--light-samples`, default 1; path tracing only).
    pub light_samples: u32,
    /// The light-transport method (`--method`, default path tracing).
    pub method: crate::transport::method::Method,
    /// Rays traced so far (closest-hit and shadow), for the benchmark.
    pub rays: u64,
    pub pool: rayon::ThreadPool,
    /// The merge radius's schedule (SPPM, VCM; default: `MergeRadius::default_for`).
    pub radius: Option<crate::transport::merging::MergeRadius>,
    /// The light-subpath methods: the light pass's splats and vertices, made at the first pass.
    buffers: Option<crate::cpu::LightPassBuffers>,
    /// Radiosity's patch size and form-factor rays (default: `RadiositySettings::default`).
    pub radiosity: crate::transport::patches::RadiositySettings,
    /// Radiosity's solution, solved before the first pass.
    pub solution: Option<crate::cpu::radiosity::Solution>,
}

impl<'a> CpuBackend<'a> {
    /// The traversal the scene's BVH is built for (`bvh::Traversal`): in a large tree the
    /// CPU's single rays test a leaf's triangles four at once.
    pub const TRAVERSAL: crate::accel::bvh::Traversal = crate::accel::bvh::Traversal::Cpu;

    pub fn new(
        scene: &'a crate::layout::FlatScene,
        camera: crate::transport::camera::Camera,
        seed: u32,
        threads: usize,
    ) -> anyhow::Result<Self> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        Ok(Self {
            scene,
            camera,
            seed,
            faults: crate::transport::faults::Faults::NONE,
            light_samples: 1,
            method: crate::transport::method::Method::Path,
            rays: 0,
            pool,
            radius: None,
            buffers: None,
            radiosity: Default::default(),
            solution: None,
        })
    }
}

impl Backend for CpuBackend<'_> {
    fn name(&self) -> &'static str {
        "cpu"
    }
    fn device(&self) -> String {
        format!("{} threads", self.pool.current_num_threads())
    }
    fn provenance(&self) -> Vec<(&'static str, String)> {
        if let Some(s) = &self.solution {
            return crate::film::provenance::radiosity_provenance(
                self.radiosity,
                s.patches.len(),
                s.steps,
                s.converged,
                (s.form_factor_seconds, s.solve_seconds),
            );
        }
        let mut out = match &self.buffers {
            Some(b) if self.method.connects() => bidirectional_provenance(
                b.shadow_threshold,
                crate::transport::subpath::specular_camera_subpaths(self.method, b.radius.initial),
                b.camera_subpaths.iter().filter(|&&n| n > 1).count(),
            ),
            _ => Vec::new(),
        };
        if let Some(b) = &self.buffers {
            let pixels = self.camera.width as u64 * self.camera.height as u64;
            let n = b.radius.light_paths_for(self.method, pixels);
            out.push(("light_paths", n.to_string()));
            if self.method.merges() {
                out.extend(merging_provenance(&b.radius));
            }
        }
        out
    }
    fn adaptive_pass_until(
        &mut self,
        runs: &[super::adaptive::PixelRun],
        film: &mut Film,
        stop: &AtomicBool,
    ) -> anyhow::Result<()> {
        anyhow::ensure!(
            self.method == crate::transport::method::Method::Path,
            "adaptive sampling is available for path tracing only, not {}",
            self.method
        );
        check_film_for(self.method, film)?;
        let (scene, camera, seed, faults) = (self.scene, &self.camera, self.seed, self.faults);
        let light_samples = self.light_samples;
        self.rays += self.pool.install(|| {
            crate::cpu::render_path_runs_until(
                scene,
                camera,
                seed,
                runs,
                light_samples,
                faults,
                film,
                stop,
            )
        });
        Ok(())
    }
    fn pass_until(
        &mut self,
        first: u32,
        count: u32,
        film: &mut Film,
        stop: &AtomicBool,
    ) -> anyhow::Result<()> {
        let (scene, camera, seed, faults) = (self.scene, &self.camera, self.seed, self.faults);
        let light_samples = self.light_samples;
        let method = self.method;
        if method.splats() {
            check_film_for(method, film)?;
            let radius = self.radius.unwrap_or_else(|| {
                crate::transport::merging::MergeRadius::default_for(scene, camera, method)
            });
            let buffers = self.buffers.get_or_insert_with(|| {
                crate::cpu::LightPassBuffers::new(scene, camera, method, radius)
            });
            self.rays += self.pool.install(|| {
                crate::cpu::render_iterations_until(
                    scene, camera, seed, first, count, method, faults, buffers, film, stop,
                )
            });
            return Ok(());
        }
        check_film_for(method, film)?;
        if method == crate::transport::method::Method::Radiosity {
            if self.solution.is_none() {
                let patches =
                    crate::transport::patches::Patches::build(scene, self.radiosity.patch_size)?;
                let settings = self.radiosity;
                let (solution, rays) = self.pool.install(|| {
                    crate::cpu::radiosity::solve(scene, patches, seed, settings.patch_rays, faults)
                });
                self.rays += rays;
                self.solution = Some(solution);
            }
            let solution = self.solution.as_ref().expect("solved above");
            self.rays += self.pool.install(|| {
                crate::cpu::render_radiosity_pass_until(
                    scene, camera, solution, seed, first, count, faults, film, stop,
                )
            });
            return Ok(());
        }
        if method == crate::transport::method::Method::Whitted {
            self.rays += self.pool.install(|| {
                crate::cpu::render_whitted_pass_until(
                    scene, camera, seed, first, count, faults, film, stop,
                )
            });
            return Ok(());
        }
        self.rays += self.pool.install(|| {
            crate::cpu::render_pass_until(
                scene,
                camera,
                seed,
                first,
                count,
                light_samples,
                faults,
                film,
                stop,
            )
        });
        Ok(())
    }
}
