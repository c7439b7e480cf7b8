//! The GPU renderer's radiosity solve (`super::super::radiosity` holds its kernels and
//! bindings): steps 1-3 of `src/cpu/radiosity.rs` on the device, once, before the first pass.

use super::GpuRenderer;
use crate::gpu::pipeline::{storage, upload};
use crate::gpu::radiosity::{
    check_patches_fit, GpuSolution, RadiosityParams, Solved, RAYS_PER_DISPATCH, SOLVE_WORKGROUP,
};
use crate::gpu::shader::Residency;
use crate::transport::patches::{
    relative_change, Patches, RadiositySettings, JACOBI_TOLERANCE, MAX_JACOBI_STEPS,
};
use anyhow::{bail, Result};
use glam::Vec3;
use std::time::Instant;

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
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
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
                entry(0, &params_buffer),
                entry(1, &grids),
                entry(2, &table),
                entry(3, &form_factors),
                entry(4, &radiosity),
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
                pass.set_bind_group(1, &r.empty_group, &[]);
                pass.set_bind_group(2, &bind_group, &[]);
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
            _params: params_buffer,
            _grids: grids,
            _table: table,
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
                (s.form_factor_seconds, s.solve_seconds),
            ),
            None => Vec::new(),
        }
    }
}
