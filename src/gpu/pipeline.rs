//! Making the GPU objects the renderer uses: scene arrays uploaded as laid out on the host,
//! storage buffers, the scene's bind-group layout and compute pipelines.

use super::shader::Residency;
use crate::layout::FlatScene;
use bytemuck::Pod;
use wgpu::util::DeviceExt;

/// Uploads one scene array as it is laid out on the host.
pub(super) fn upload<T: Pod>(
    device: &wgpu::Device,
    residency: Residency,
    label: &str,
    data: &[T],
) -> wgpu::Buffer {
    // wgpu refuses zero-sized bindings: an empty array (a scene without spheres) is one zeroed
    // element that nothing references.
    let zero = [T::zeroed()];
    let data: &[T] = if data.is_empty() { &zero } else { data };
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(data),
        usage: match residency {
            Residency::Storage => wgpu::BufferUsages::STORAGE,
            Residency::Uniform => wgpu::BufferUsages::UNIFORM,
        },
    })
}

/// The primitive references packed four to a vec4<u32>, as both residencies declare them (the
/// BVH build pads `prims` to a multiple of four with `PRIM_PADDING`; only an empty scene's
/// array is zero-filled here).
pub(super) fn packed_prims(scene: &FlatScene) -> Vec<[u32; 4]> {
    scene
        .prims
        .chunks(4)
        .map(|c| {
            let mut v = [0u32; 4];
            v[..c.len()].copy_from_slice(c);
            v
        })
        .collect()
}

/// A storage buffer that copies can also read and write.
pub(super) fn storage(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The compiled kernel, and the pipeline cache its pipelines are built through, if any
/// (`pipeline_cache`).
#[derive(Clone, Copy)]
pub(super) struct Kernel<'a> {
    pub module: &'a wgpu::ShaderModule,
    pub cache: Option<&'a wgpu::PipelineCache>,
}

/// A compute pipeline for entry point `entry` of the kernel, over bind groups of `layouts`.
pub(super) fn compute_pipeline(
    device: &wgpu::Device,
    kernel: Kernel<'_>,
    layouts: &[&wgpu::BindGroupLayout],
    entry: &str,
) -> wgpu::ComputePipeline {
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(|l| Some(*l)).collect();
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(entry),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(&pipeline_layout),
        module: kernel.module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: kernel.cache,
    })
}

/// Bind-group entries 0, 1, … for whole buffers, in order.
pub(super) fn buffer_entries<'a>(
    buffers: impl Iterator<Item = &'a wgpu::Buffer>,
) -> Vec<wgpu::BindGroupEntry<'a>> {
    buffers
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect()
}

/// The bindings of `shaders/scene.wgsl`: the six scene arrays (storage or uniform), the frame
/// (uniform), the pass sums (read-write storage), adaptive sampling's pixel runs (storage).
pub(super) fn bind_group_layout(
    device: &wgpu::Device,
    residency: Residency,
) -> wgpu::BindGroupLayout {
    let buffer = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let scene_array = match residency {
        Residency::Storage => wgpu::BufferBindingType::Storage { read_only: true },
        Residency::Uniform => wgpu::BufferBindingType::Uniform,
    };
    let read_write = wgpu::BufferBindingType::Storage { read_only: false };
    let mut entries: Vec<_> = (0..6).map(|b| buffer(b, scene_array)).collect();
    entries.push(buffer(6, wgpu::BufferBindingType::Uniform));
    entries.push(buffer(7, read_write));
    entries.push(buffer(
        8,
        wgpu::BufferBindingType::Storage { read_only: true },
    ));
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("scene"),
        entries: &entries,
    })
}
