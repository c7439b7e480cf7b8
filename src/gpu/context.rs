//! Getting a GPU: instance, adapter, device and queue, and nothing else (wgpu's hello_compute
//! idiom). The renderer takes `&Device, &Queue`, so the CLI, tests and benchmarks share one path.

use std::fmt;

/// What to install where no adapter exists (Debian/Ubuntu; Mesa's software Vulkan).
pub const LAVAPIPE_HINT: &str = "sudo apt-get install -y mesa-vulkan-drivers";

/// A device ready for work, with the adapter it came from.
pub struct Gpu {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
}

/// Why no GPU could be had.
#[derive(Debug)]
pub enum GpuError {
    NoAdapter,
    NoMatch { wanted: String, found: Vec<String> },
    Device(String),
}

impl fmt::Display for GpuError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GpuError::NoAdapter => write!(
                f,
                "no GPU adapter found (Vulkan, Metal or DX12); for software Vulkan on Debian or \
                 Ubuntu: {LAVAPIPE_HINT}"
            ),
            GpuError::NoMatch { wanted, found } => write!(
                f,
                "no adapter name contains `{wanted}`; found: {}",
                found.join("; ")
            ),
            GpuError::Device(e) => write!(f, "the adapter refused a device: {e}"),
        }
    }
}

impl std::error::Error for GpuError {}

/// The backends hexray looks at: Vulkan, Metal, DX12 (WGPU_BACKEND overrides).
fn backends() -> wgpu::Backends {
    wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY)
}

fn instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends();
    wgpu::Instance::new(desc)
}

/// Every adapter the system offers, best first: discrete, integrated, virtual, then CPU
/// (lavapipe/llvmpipe).
pub fn adapters() -> Vec<wgpu::Adapter> {
    let mut list = pollster::block_on(instance().enumerate_adapters(backends()));
    list.sort_by_key(|a| rank(&a.get_info()));
    list
}

fn rank(info: &wgpu::AdapterInfo) -> u8 {
    match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    }
}

/// The merge radius a render on this adapter takes by default, from `base` (the CPU backend's
/// default, with any `--alpha`): on a hardware GPU a share of it
/// (`merging::HARDWARE_GPU_RADIUS_SCALE`), since its renders run many more iterations; a
/// software adapter (lavapipe) keeps `base`.
pub fn default_merge_radius(
    info: &wgpu::AdapterInfo,
    base: crate::transport::merging::MergeRadius,
) -> crate::transport::merging::MergeRadius {
    if info.device_type == wgpu::DeviceType::Cpu {
        base
    } else {
        base.for_hardware_gpu()
    }
}

/// One line about an adapter: name, type, backend, driver.
pub fn describe(info: &wgpu::AdapterInfo) -> String {
    format!(
        "{} ({:?}, {:?}, driver {} {})",
        info.name, info.device_type, info.backend, info.driver, info.driver_info
    )
}

/// The best adapter, or the first whose name contains `wanted` (case-insensitive), with a device.
pub fn acquire(wanted: Option<&str>) -> Result<Gpu, GpuError> {
    let list = adapters();
    if list.is_empty() {
        return Err(GpuError::NoAdapter);
    }
    let adapter = match wanted {
        None => list.into_iter().next().unwrap(),
        Some(w) => {
            let names: Vec<String> = list.iter().map(|a| describe(&a.get_info())).collect();
            list.into_iter()
                .find(|a| a.get_info().name.to_lowercase().contains(&w.to_lowercase()))
                .ok_or(GpuError::NoMatch {
                    wanted: w.to_string(),
                    found: names,
                })?
        }
    };
    let info = adapter.get_info();
    let have = adapter.limits();
    // WebGPU's default limits, with buffer sizes as large as the adapter allows, for big
    // scenes and images, and as many storage buffers per stage as it allows: with the scene in
    // storage buffers, path tracing binds 8 (WebGPU's default), the light pass 9 and the camera
    // pass 13.
    let limits = wgpu::Limits {
        max_storage_buffer_binding_size: have.max_storage_buffer_binding_size,
        max_buffer_size: have.max_buffer_size,
        max_storage_buffers_per_shader_stage: have.max_storage_buffers_per_shader_stage,
        ..wgpu::Limits::default()
    };
    // Compiled pipelines kept across runs, where the adapter offers it (`pipeline_cache`).
    let features = adapter.features() & wgpu::Features::PIPELINE_CACHE;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("hexray"),
        required_features: features,
        required_limits: limits,
        ..Default::default()
    }))
    .map_err(|e| GpuError::Device(e.to_string()))?;
    Ok(Gpu {
        adapter,
        device,
        queue,
        info,
    })
}
