//! The GPU backend: the whole per-pixel path loop in a WGSL compute shader (`shaders/`),
//! run through wgpu.

pub mod bidirectional;
pub mod context;
pub mod render;
pub mod shader;
#[cfg(feature = "stage-times")]
pub mod stage_times;

pub use context::{acquire, Gpu, GpuError};
pub use render::{Checks, GpuRenderer};
pub use shader::Residency;

use crate::film::Film;

/// The GPU renderer as a [`crate::render::Backend`].
pub struct GpuBackend {
    pub renderer: GpuRenderer,
    pub adapter: String,
}

impl crate::render::Backend for GpuBackend {
    fn name(&self) -> &'static str {
        "gpu"
    }
    fn device(&self) -> String {
        self.adapter.clone()
    }
    fn pass(&mut self, first: u32, count: u32, film: &mut Film) -> anyhow::Result<()> {
        self.renderer.render(first, count, film)
    }
    fn provenance(&self) -> Vec<(&'static str, String)> {
        self.renderer.provenance()
    }
}
