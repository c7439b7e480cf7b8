//! The GPU backend: the whole per-pixel path loop in a WGSL compute shader (`shaders/`),
//! run through wgpu.

pub mod bidirectional;
pub mod context;
pub mod frame;
pub mod limits;
pub mod pipeline;
pub mod pipeline_cache;
pub mod radiosity;
pub mod renderer;
pub mod shader;
#[cfg(feature = "stage-times")]
pub mod stage_times;

pub use context::{acquire, Gpu, GpuError};
pub use renderer::{Checks, GpuRenderer};
pub use shader::Residency;
