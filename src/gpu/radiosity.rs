//! The GPU's radiosity: the kernels of `shaders/radiosity.wgsl` (`form_factor_rows`,
//! `jacobi_step`, `gather_indirect`), the parameters and bindings they share with the image
//! pass (`radiosity_pass`, bind group 2), and what fits the device; the solve itself is
//! `renderer::radiosity`. The CPU's is `src/cpu/radiosity.rs`, step for step.
//!
//! The solve runs once, before the first pass: the form-factor rows in dispatches of
//! [`RAYS_PER_DISPATCH`] rays per patch (one invocation per patch, which owns its row, so no
//! atomics), then Jacobi steps that ping-pong between two halves of one buffer, each step's
//! result read back so that the host stops at the same criterion as the CPU (the largest
//! relative change below `JACOBI_TOLERANCE`), then the indirect light per patch.

use super::limits::largest_binding;
use super::pipeline::{compute_pipeline, Kernel};
use crate::layout::FlatScene;
use crate::transport::faults::Faults;
use crate::transport::patches::{
    check_count, patches_within, Patches, RadiositySettings, TooManyPatches, MAX_PATCHES,
};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Form-factor rays per patch in one dispatch, so that a dispatch stays short on a GPU with a
/// watchdog.
pub const RAYS_PER_DISPATCH: u32 = 64;

/// Invocations per workgroup of the solve kernels (`@workgroup_size(64, 1, 1)`).
pub(in crate::gpu) const SOLVE_WORKGROUP: u32 = 64;

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
    /// The parameters and the patch table, bound in `bind_group` and held as long as it is.
    pub(in crate::gpu) _params: wgpu::Buffer,
    pub(in crate::gpu) _grids: wgpu::Buffer,
    pub(in crate::gpu) _table: wgpu::Buffer,
    pub(in crate::gpu) form_factors: wgpu::Buffer,
    pub(in crate::gpu) radiosity: wgpu::Buffer,
    pub(in crate::gpu) patches: Patches,
    /// Which half of the radiosity buffer holds the solution (0 or N).
    pub(in crate::gpu) solution_offset: u32,
    pub(in crate::gpu) steps: u32,
    pub(in crate::gpu) converged: bool,
    pub(in crate::gpu) form_factor_seconds: f64,
    pub(in crate::gpu) solve_seconds: f64,
}

/// Radiosity's kernels, its bind group's layout, what it solves on, and (once solved) its
/// buffers.
pub struct Radiosity {
    pub(in crate::gpu) layout: wgpu::BindGroupLayout,
    /// Group 1 of radiosity's pipelines, empty: the light-subpath methods' group in the module,
    /// which radiosity's entry points do not use (theirs is group 2).
    pub(in crate::gpu) empty_layout: wgpu::BindGroupLayout,
    pub(in crate::gpu) empty_group: wgpu::BindGroup,
    pub(in crate::gpu) rows: wgpu::ComputePipeline,
    pub(in crate::gpu) jacobi: wgpu::ComputePipeline,
    pub(in crate::gpu) gather: wgpu::ComputePipeline,
    /// The scene's triangles, spheres and materials, for cutting patches at the first pass.
    pub(in crate::gpu) scene: FlatScene,
    seed: u32,
    faults: Faults,
    pub settings: RadiositySettings,
    pub(in crate::gpu) solved: Option<Solved>,
}

/// Group 2's layout of the radiosity kernels: bindings 0 (the parameters), 1 and 2 (the patch
/// table), all read-only storage, and 3 and 4 (form factors and radiosity, read-write).
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
            entry(0, read),
            entry(1, read),
            entry(2, read),
            entry(3, write),
            entry(4, write),
        ],
    })
}

impl Radiosity {
    pub(in crate::gpu) fn new(
        device: &wgpu::Device,
        kernel: Kernel<'_>,
        scene_layout: &wgpu::BindGroupLayout,
        layout: wgpu::BindGroupLayout,
        scene: &FlatScene,
        seed: u32,
        faults: Faults,
    ) -> Radiosity {
        let empty_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("empty"),
            entries: &[],
        });
        let empty_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("empty"),
            layout: &empty_layout,
            entries: &[],
        });
        let pipeline = |entry| {
            compute_pipeline(
                device,
                kernel,
                &[scene_layout, &empty_layout, &layout],
                entry,
            )
        };
        let (rows, jacobi, gather) = (
            pipeline("form_factor_rows"),
            pipeline("jacobi_step"),
            pipeline("gather_indirect"),
        );
        Radiosity {
            empty_layout,
            empty_group,
            rows,
            jacobi,
            gather,
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

    pub(in crate::gpu) fn params(&self, patches: &Patches) -> RadiosityParams {
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
