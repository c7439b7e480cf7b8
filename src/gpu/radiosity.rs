//! The GPU's radiosity: the host side of the solve kernels of `shaders/radiosity.wgsl`
//! (`form_factor_rows`, `jacobi_step`, `gather_indirect`) and the buffers its image pass
//! (`radiosity_pass`) reads. The CPU's is `src/cpu/radiosity.rs`, step for step.
//!
//! The solve runs once, before the first pass: the form-factor rows in dispatches of
//! [`RAYS_PER_DISPATCH`] rays per patch (one invocation per patch, which owns its row, so no
//! atomics), then Jacobi steps that ping-pong between two halves of one buffer, each step's
//! result read back so that the host stops at the same criterion as the CPU (the largest
//! relative change below `JACOBI_TOLERANCE`), then the indirect light per patch.

use super::limits::largest_binding;
use super::pipeline::{compute_pipeline, storage, upload};
use super::renderer::GpuRenderer;
use super::shader::Residency;
use crate::layout::FlatScene;
use crate::transport::faults::Faults;
use crate::transport::patches::{
    check_count, patches_within, relative_change, Patches, RadiositySettings, TooManyPatches,
    JACOBI_TOLERANCE, MAX_JACOBI_STEPS, MAX_PATCHES,
};
use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::time::Instant;

/// Form-factor rays per patch in one dispatch, so that a dispatch stays short on a GPU with a
/// watchdog.
pub const RAYS_PER_DISPATCH: u32 = 64;

/// Invocations per workgroup of the solve kernels (`@workgroup_size(64, 1, 1)`).
const SOLVE_WORKGROUP: u32 = 64;

/// One dispatch of the solve (`RadiosityParams` in `shaders/radiosity.wgsl`). Three vec4s.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct RadiosityParams {
    pub patch_count: u32,
    pub rays_per_patch: u32,
    pub first_ray: u32,
    pub ray_count: u32,
    pub seed: u32,
    pub triangle_count: u32,
    /// Offsets in the radiosity buffer of the step's input and output (0 or N).
    pub step_input: u32,
    pub step_output: u32,
    pub form_factor_scale: f32,
    pub uniform_directions: u32,
    pub indirect_with_direct: u32,
    pub pad0: u32,
}

/// The most patches this device solves: the form-factor matrix in one storage binding, and
/// at most the CPU's [`MAX_PATCHES`]; with the reason, for [`check_count`].
pub fn patch_limit(limits: &wgpu::Limits) -> (u64, String) {
    let binding = largest_binding(limits);
    let within = patches_within(binding);
    if within < MAX_PATCHES as u64 {
        (
            within,
            format!(
                "the device binds at most {:.0} MiB of storage",
                binding as f64 / (1u64 << 20) as f64
            ),
        )
    } else {
        (
            MAX_PATCHES as u64,
            crate::transport::patches::CPU_LIMIT_REASON.to_string(),
        )
    }
}

/// Whether the patches of `scene` at `settings` fit this device (a sentence for the user if
/// not).
pub fn check_patches_fit(
    limits: &wgpu::Limits,
    scene: &FlatScene,
    settings: RadiositySettings,
) -> Result<u64, TooManyPatches> {
    let (limit, why) = patch_limit(limits);
    check_count(scene, settings.patch_size, limit, &why)
}

/// The solved state on the device.
pub(in crate::gpu) struct Solved {
    pub(in crate::gpu) bind_group: wgpu::BindGroup,
    form_factors: wgpu::Buffer,
    radiosity: wgpu::Buffer,
    pub(in crate::gpu) patches: Patches,
    /// Which half of the radiosity buffer holds the solution (0 or N).
    solution_offset: u32,
    pub(in crate::gpu) steps: u32,
    pub(in crate::gpu) converged: bool,
    pub(in crate::gpu) form_factor_seconds: f64,
    pub(in crate::gpu) solve_seconds: f64,
}

/// Radiosity's kernels, its bind group's layout, what it solves on, and (once solved) its
/// buffers.
pub struct Radiosity {
    pub(in crate::gpu) layout: wgpu::BindGroupLayout,
    rows: wgpu::ComputePipeline,
    jacobi: wgpu::ComputePipeline,
    gather: wgpu::ComputePipeline,
    /// The scene's triangles, spheres and materials, for cutting patches at the first pass.
    scene: FlatScene,
    seed: u32,
    faults: Faults,
    pub settings: RadiositySettings,
    pub(in crate::gpu) solved: Option<Solved>,
}

/// Group 1's layout of the radiosity kernels: bindings 7 (the parameters, uniform), 8 and 9 (the
/// patch table, read-only), 10 and 11 (form factors and radiosity, read-write).
pub(in crate::gpu) fn radiosity_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let read = wgpu::BufferBindingType::Storage { read_only: true };
    let write = wgpu::BufferBindingType::Storage { read_only: false };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("radiosity"),
        entries: &[
            entry(7, wgpu::BufferBindingType::Uniform),
            entry(8, read),
            entry(9, read),
            entry(10, write),
            entry(11, write),
        ],
    })
}

impl Radiosity {
    pub(in crate::gpu) fn new(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        scene_layout: &wgpu::BindGroupLayout,
        layout: wgpu::BindGroupLayout,
        scene: &FlatScene,
        seed: u32,
        faults: Faults,
    ) -> Radiosity {
        let pipeline = |entry| compute_pipeline(device, module, &[scene_layout, &layout], entry);
        Radiosity {
            rows: pipeline("form_factor_rows"),
            jacobi: pipeline("jacobi_step"),
            gather: pipeline("gather_indirect"),
            layout,
            scene: FlatScene {
                triangles: scene.triangles.clone(),
                spheres: scene.spheres.clone(),
                materials: scene.materials.clone(),
                ..Default::default()
            },
            seed,
            faults,
            settings: RadiositySettings::default(),
            solved: None,
        }
    }

    fn params(&self, patches: &Patches) -> RadiosityParams {
        RadiosityParams {
            patch_count: patches.len() as u32,
            rays_per_patch: self.settings.patch_rays,
            first_ray: 0,
            ray_count: 0,
            seed: self.seed,
            triangle_count: self.scene.triangles.len() as u32,
            step_input: 0,
            step_output: 0,
            form_factor_scale: self.faults.form_factor_scale,
            uniform_directions: self.faults.form_factor_uniform_directions as u32,
            indirect_with_direct: self.faults.indirect_with_direct as u32,
            pad0: 0,
        }
    }
}

/// What the tests read of a GPU solution: the form factors (row-major), each patch's radiance
/// and indirect light, and the Jacobi steps.
#[derive(Clone, Debug)]
pub struct GpuSolution {
    pub form_factors: Vec<f32>,
    pub radiance: Vec<Vec3>,
    pub indirect: Vec<Vec3>,
    pub steps: u32,
    pub converged: bool,
}

impl GpuRenderer {
    /// Radiosity's patch size and form-factor rays (before the first pass; default
    /// `RadiositySettings::default`).
    pub fn set_radiosity(&mut self, settings: RadiositySettings) {
        if let Some(r) = &mut self.radiosity {
            r.settings = settings;
            r.solved = None;
        }
    }

    /// Solves the scene's radiosity on the device if it is not yet solved (steps 1-3 of
    /// `src/cpu/radiosity.rs`).
    pub(in crate::gpu) fn solve_radiosity(&mut self) -> Result<()> {
        let Some(r) = &self.radiosity else {
            return Ok(());
        };
        if r.solved.is_some() {
            return Ok(());
        }
        let device = &self.device;
        let limits = device.limits();
        check_patches_fit(&limits, &r.scene, r.settings).map_err(anyhow::Error::msg)?;
        let patches = Patches::build(&r.scene, r.settings.patch_size)?;
        let n = patches.len() as u32;
        if n == 0 {
            bail!("radiosity: the scene has no diffuse surface to cut into patches");
        }
        let start = Instant::now();
        let grids = upload(device, Residency::Storage, "patch grids", &patches.grids);
        let table = upload(device, Residency::Storage, "patches", &patches.patches);
        let form_factors = storage(device, "form factors", 4 * n as u64 * n as u64);
        let radiosity = storage(device, "radiosity", 16 * 3 * n as u64);
        let params_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("radiosity params"),
            size: std::mem::size_of::<RadiosityParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            }
        }
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("radiosity"),
            layout: &r.layout,
            entries: &[
                entry(7, &params_buffer),
                entry(8, &grids),
                entry(9, &table),
                entry(10, &form_factors),
                entry(11, &radiosity),
            ],
        });
        let base = r.params(&patches);
        let groups = n.div_ceil(SOLVE_WORKGROUP);
        let run = |pipeline: &wgpu::ComputePipeline, params: RadiosityParams| {
            // One submission per dispatch: the parameters written land before it.
            self.queue
                .write_buffer(&params_buffer, 0, bytemuck::bytes_of(&params));
            let mut encoder = device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &self.bind_group, &[]);
                pass.set_bind_group(1, &bind_group, &[]);
                pass.dispatch_workgroups(groups, 1, 1);
            }
            self.queue.submit([encoder.finish()]);
        };

        // Step 1 - form factors, RAYS_PER_DISPATCH rays of every row at a time.
        let rays = r.settings.patch_rays;
        let mut first = 0;
        while first < rays {
            let count = RAYS_PER_DISPATCH.min(rays - first);
            run(
                &r.rows,
                RadiosityParams {
                    first_ray: first,
                    ray_count: count,
                    ..base
                },
            );
            first += count;
        }
        let _ = device.poll(wgpu::PollType::wait_indefinitely());
        let form_factor_seconds = start.elapsed().as_secs_f64();
        self.check_device()?;

        // Step 2 - Jacobi from L⁰ = Le, each step read back for the stopping rule.
        let start = Instant::now();
        let mut previous: Vec<Vec3> = patches
            .patches
            .iter()
            .map(|p| Vec3::from(p.emission))
            .collect();
        let first_half: Vec<[f32; 4]> = previous.iter().map(|l| l.extend(0.0).into()).collect();
        self.queue
            .write_buffer(&radiosity, 0, bytemuck::cast_slice(&first_half));
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("radiosity readback"),
            size: 16 * n as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let (mut steps, mut converged, mut source) = (0, false, 0u32);
        while steps < MAX_JACOBI_STEPS {
            let target = n - source;
            run(
                &r.jacobi,
                RadiosityParams {
                    step_input: source,
                    step_output: target,
                    ..base
                },
            );
            let mut encoder = device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(
                &radiosity,
                16 * target as u64,
                &readback,
                0,
                Some(16 * n as u64),
            );
            self.queue.submit([encoder.finish()]);
            let next: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&self.read_buffer(&readback)?);
            let next: Vec<Vec3> = next.iter().map(|v| Vec3::from_slice(v)).collect();
            let change = next
                .iter()
                .zip(&previous)
                .map(|(a, b)| relative_change(*a, *b))
                .fold(0.0f32, f32::max);
            previous = next;
            source = target;
            steps += 1;
            if change < JACOBI_TOLERANCE {
                converged = true;
                break;
            }
        }

        // Step 3 - the indirect light of each patch from the solution.
        run(
            &r.gather,
            RadiosityParams {
                step_input: source,
                ..base
            },
        );
        let _ = device.poll(wgpu::PollType::wait_indefinitely());
        self.check_device()?;
        let solve_seconds = start.elapsed().as_secs_f64();
        let r = self.radiosity.as_mut().expect("radiosity's kernels");
        r.solved = Some(Solved {
            bind_group,
            form_factors,
            radiosity,
            patches,
            solution_offset: source,
            steps,
            converged,
            form_factor_seconds,
            solve_seconds,
        });
        Ok(())
    }

    /// Radiosity's solution as the device holds it, solving first if needed (tests).
    pub fn radiosity_solution(&mut self) -> Result<GpuSolution> {
        self.solve_radiosity()?;
        let Some(solved) = self.radiosity.as_ref().and_then(|r| r.solved.as_ref()) else {
            bail!("not a radiosity renderer");
        };
        let n = solved.patches.len() as u64;
        let read = |buffer: &wgpu::Buffer, offset: u64, size: u64| -> Result<Vec<u8>> {
            let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("solution readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut encoder = self.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(buffer, offset, &readback, 0, Some(size));
            self.queue.submit([encoder.finish()]);
            self.read_buffer(&readback)
        };
        let vec3s = |bytes: Vec<u8>| -> Vec<Vec3> {
            let v: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes);
            v.iter().map(|x| Vec3::from_slice(x)).collect()
        };
        Ok(GpuSolution {
            form_factors: bytemuck::pod_collect_to_vec(&read(&solved.form_factors, 0, 4 * n * n)?),
            radiance: vec3s(read(
                &solved.radiosity,
                16 * solved.solution_offset as u64,
                16 * n,
            )?),
            indirect: vec3s(read(&solved.radiosity, 16 * 2 * n, 16 * n)?),
            steps: solved.steps,
            converged: solved.converged,
        })
    }

    /// Radiosity's provenance (patches, steps, solve time), once solved.
    pub(in crate::gpu) fn radiosity_provenance(&self) -> Vec<(&'static str, String)> {
        match self
            .radiosity
            .as_ref()
            .and_then(|r| r.solved.as_ref().map(|s| (r, s)))
        {
            Some((r, s)) => crate::film::provenance::radiosity_provenance(
                r.settings,
                s.patches.len(),
                s.steps,
                s.converged,
                s.form_factor_seconds + s.solve_seconds,
            ),
            None => Vec::new(),
        }
    }
}
