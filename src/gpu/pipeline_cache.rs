//! Compiled pipelines kept across runs: wgpu's `PipelineCache` (Vulkan's VkPipelineCache),
//! read from a file before the kernel's pipelines are built and written back after.
//!
//! Where the adapter offers it (`Features::PIPELINE_CACHE`, Vulkan only), the driver may take
//! a pipeline from the cache instead of compiling it again. Drivers keep caches of their own
//! too (Mesa's disk cache, NVIDIA's compute cache), so what this saves depends on the driver
//! (docs/design/gpu.md, "The first image"). The file is named by the adapter
//! (`wgpu::util::pipeline_cache_key`); wgpu checks its header and starts empty from data of
//! another driver or wgpu version (`fallback`).
//!
//! Where: `$HEXRAY_PIPELINE_CACHE` (a folder; `off` for none), else
//! `$XDG_CACHE_HOME/hexray`, else `$HOME/.cache/hexray`.

use std::path::{Path, PathBuf};

/// A pipeline cache and the file it came from and goes back to.
pub struct PipelineCacheFile {
    pub cache: wgpu::PipelineCache,
    pub path: PathBuf,
    /// The bytes read from the file (0: none, a first run).
    pub loaded_bytes: usize,
}

/// The folder for pipeline caches (the module's text); None where caching is off or no folder
/// is known.
pub fn cache_dir() -> Option<PathBuf> {
    let var = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty());
    if let Some(dir) = var("HEXRAY_PIPELINE_CACHE") {
        return (dir != "off").then(|| PathBuf::from(dir));
    }
    var("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| var("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .map(|d| d.join("hexray"))
}

/// The device's pipeline cache from the file for its adapter in `dir`, or an empty one where the
/// file is missing or unreadable; None where the device has no `PIPELINE_CACHE` feature or the
/// adapter's backend keeps no application cache.
pub fn open(
    device: &wgpu::Device,
    info: &wgpu::AdapterInfo,
    dir: &Path,
) -> Option<PipelineCacheFile> {
    if !device.features().contains(wgpu::Features::PIPELINE_CACHE) {
        return None;
    }
    let path = dir.join(wgpu::util::pipeline_cache_key(info)?);
    let data = std::fs::read(&path).ok();
    // SAFETY: the data is what `PipelineCache::get_data` returned in an earlier run (`save`), or
    // anything else found under that name: wgpu validates its header (adapter, driver and wgpu
    // version, length and hash of the payload) and, with `fallback`, starts an empty cache
    // from data that fails the check.
    let cache = unsafe {
        device.create_pipeline_cache(&wgpu::PipelineCacheDescriptor {
            label: Some("hexray pipelines"),
            data: data.as_deref(),
            fallback: true,
        })
    };
    Some(PipelineCacheFile {
        cache,
        path,
        loaded_bytes: data.map_or(0, |d| d.len()),
    })
}

impl PipelineCacheFile {
    /// Writes the cache's data to its file (a temporary file renamed over it, so that a
    /// concurrent run reads the old file or the new one whole). Returns the bytes written (0
    /// where the driver gave no data).
    pub fn save(&self) -> std::io::Result<usize> {
        let Some(data) = self.cache.get_data() else {
            return Ok(0);
        };
        if let Some(dir) = self.path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let tmp = self
            .path
            .with_extension(format!("tmp{}", std::process::id()));
        std::fs::write(&tmp, &data)?;
        std::fs::rename(&tmp, &self.path).inspect_err(|_| {
            let _ = std::fs::remove_file(&tmp);
        })?;
        Ok(data.len())
    }
}
