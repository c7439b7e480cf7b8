//! The GPU renderer as a [`Backend`].

use super::Backend;
use crate::film::Film;
use crate::gpu::GpuRenderer;
use std::sync::atomic::AtomicBool;

/// The GPU renderer as a [`Backend`].
pub struct GpuBackend {
    pub renderer: GpuRenderer,
    pub adapter: String,
}

impl Backend for GpuBackend {
    fn name(&self) -> &'static str {
        "gpu"
    }
    fn device(&self) -> String {
        self.adapter.clone()
    }
    fn pass_until(
        &mut self,
        first: u32,
        count: u32,
        film: &mut Film,
        stop: &AtomicBool,
    ) -> anyhow::Result<()> {
        self.renderer.render_until(first, count, film, stop)
    }
    fn adaptive_pass_until(
        &mut self,
        runs: &[super::adaptive::PixelRun],
        film: &mut Film,
        stop: &AtomicBool,
    ) -> anyhow::Result<()> {
        self.renderer.adaptive_pass_until(runs, film, stop)
    }
    fn provenance(&self) -> Vec<(&'static str, String)> {
        self.renderer.provenance()
    }
}
