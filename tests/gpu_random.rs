//! The GPU draws the very same random numbers as the CPU: a tiny kernel made of
//! `shaders/sampling.wgsl` and a probe entry point writes the raw bits of `draw4` for a grid of
//! (pixel, sample, dimension) keys, and they must equal `Sampler::draw4` bit for bit, for each
//! sampler.

use crate::common::gpu;
use hexray::gpu::shader::validate;
use hexray::math::sampling::{Sampler, SamplerKind};
use wgpu::util::DeviceExt;

const PROBE: &str = r#"
@group(0) @binding(0) var<storage, read_write> out: array<vec4<u32>>;

@compute @workgroup_size(64)
fn probe(@builtin(global_invocation_id) g: vec3<u32>) {
    let i = g.x;
    // 16 pixels x 8 samples x 8 dimension blocks, seed 12345; pixels and samples spread out so
    // large keys are covered too (past 2^17 samples: a Sobol stream's second randomisation).
    let pixel = (i % 16u) * 40503u;
    let sample = ((i / 16u) % 8u) * 29989u;
    let dim = i / 128u;
    out[i] = bitcast<vec4<u32>>(draw4(Sampler(12345u, pixel, sample, KIND), dim));
}
"#;

#[test]
fn gpu_random_streams_equal_the_cpu_bit_for_bit() {
    for kind in [SamplerKind::Independent, SamplerKind::Sobol] {
        streams_equal(kind);
    }
}

fn streams_equal(kind: SamplerKind) {
    let Some(gpu) = gpu() else { return };
    let source = format!(
        "{}\nconst KIND: u32 = {}u;\n{PROBE}",
        include_str!("../shaders/sampling.wgsl"),
        kind.code()
    );
    validate(&source).unwrap();
    let n = 16 * 8 * 8u32;
    let (device, queue) = (&gpu.device, &gpu.queue);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("random probe"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &module,
        entry_point: Some("probe"),
        compilation_options: Default::default(),
        cache: None,
    });
    let out = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: &vec![0u8; n as usize * 16],
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    });
    let read = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: n as u64 * 16,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: out.as_entire_binding(),
        }],
    });
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(n / 64, 1, 1);
    }
    enc.copy_buffer_to_buffer(&out, 0, &read, 0, None);
    queue.submit([enc.finish()]);
    read.slice(..)
        .map_async(wgpu::MapMode::Read, |r| r.unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let bytes = read.slice(..).get_mapped_range().unwrap().to_vec();
    let got: Vec<[u32; 4]> = bytemuck::pod_collect_to_vec(&bytes);
    for i in 0..n {
        let (pixel, sample, dim) = ((i % 16) * 40503, ((i / 16) % 8) * 29989, i / 128);
        let want = Sampler::of(kind, 12345, pixel, sample)
            .draw4(dim)
            .map(f32::to_bits);
        assert_eq!(
            got[i as usize], want,
            "{kind}: pixel {pixel} sample {sample} dim {dim}"
        );
    }
}
