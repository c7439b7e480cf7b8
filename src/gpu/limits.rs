//! What fits the device: the scene arrays against the binding limits of each residency, the
//! image against the largest storage binding (cut into film bands of whole rows), and the
//! residency a device prefers. Each refusal is a sentence for the user, said before any work.

use super::frame::{tally_words, PixelSums};
use super::shader::{ArrayLengths, Residency};
use crate::layout::FlatScene;
use crate::transport::method::Method;

/// The lengths the uniform residency declares.
pub fn array_lengths(scene: &FlatScene) -> ArrayLengths {
    ArrayLengths {
        triangles: scene.triangles.len(),
        spheres: scene.spheres.len(),
        materials: scene.materials.len(),
        emitters: scene.emitters.len(),
        nodes: scene.nodes.len(),
        prims: scene.prims.len().div_ceil(4),
        stack_size: crate::accel::bvh::stack_size(&scene.nodes),
    }
}

/// The scene arrays the kernel binds, by name, with their sizes in bytes as uploaded.
pub fn scene_arrays(scene: &FlatScene) -> [(&'static str, usize); 6] {
    // An empty array is uploaded as one zeroed element (`upload`).
    let at_least = |bytes: usize, one: usize| bytes.max(one);
    [
        (
            "triangles",
            at_least(std::mem::size_of_val(&scene.triangles[..]), 64),
        ),
        (
            "spheres",
            at_least(std::mem::size_of_val(&scene.spheres[..]), 32),
        ),
        (
            "materials",
            at_least(std::mem::size_of_val(&scene.materials[..]), 32),
        ),
        (
            "emitters",
            at_least(std::mem::size_of_val(&scene.emitters[..]), 16),
        ),
        (
            "nodes",
            at_least(std::mem::size_of_val(&scene.nodes[..]), 128),
        ),
        ("prims", at_least(16 * scene.prims.len().div_ceil(4), 16)),
    ]
}

/// Bytes of one pixel's pass sums on the device.
pub(super) const PIXEL_SUMS_BYTES: u64 = std::mem::size_of::<PixelSums>() as u64;
/// Bytes of one pixel run in the runs buffer (`pixel_runs` in `shaders/scene.wgsl`).
pub(super) const PIXEL_RUN_BYTES: u64 = 16;

/// The largest buffer the device binds as storage.
pub(super) fn largest_binding(limits: &wgpu::Limits) -> u64 {
    limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size)
}

/// Whether a `width` x `height` render with `method` fits this device's largest storage
/// binding; if not, a sentence for the user. The per-pixel buffers are cut into film bands of
/// whole rows (path tracing: `GpuRenderer::film_rows`; the methods that splat: the band of
/// their tallies, `bidirectional::splat_band_rows`), so any image whose single row fits
/// renders: on lavapipe's 128 MiB, rows of up to 2.8 million pixels (48 bytes each).
pub fn check_image_fits(
    limits: &wgpu::Limits,
    method: Method,
    width: u32,
    height: u32,
) -> Result<(), String> {
    let limit = largest_binding(limits);
    let fits = if method.splats() {
        splat_band_rows(limit, width, height).is_some()
    } else {
        width as u64 * PIXEL_SUMS_BYTES <= limit
    };
    if fits {
        return Ok(());
    }
    Err(format!(
        "one {width}-pixel row of a render with --method {method} needs more than this adapter \
         binds in one buffer ({limit} bytes); render it narrower, or with --backend cpu"
    ))
}

/// Whether every scene array fits one binding of `residency` on a device with `limits`; if not,
/// a sentence for the user naming the array, its size, the limit and what works instead.
pub fn check_scene_fits(
    limits: &wgpu::Limits,
    residency: Residency,
    scene: &FlatScene,
) -> Result<(), String> {
    let (limit, what) = match residency {
        Residency::Storage => (largest_binding(limits), "storage buffer binding"),
        Residency::Uniform => (
            limits
                .max_uniform_buffer_binding_size
                .min(limits.max_buffer_size),
            "uniform buffer binding",
        ),
    };
    for (name, bytes) in scene_arrays(scene) {
        if bytes as u64 > limit {
            let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
            let alternative = match residency {
                Residency::Uniform => "--scene-residency storage, or --backend cpu",
                Residency::Storage => "--backend cpu (no such limit)",
            };
            return Err(format!(
                "the scene's {name} array is {:.1} MiB ({} triangles), more than this adapter's \
                 largest {what} of {:.3} MiB (lavapipe's storage limit is 128 MiB, about 2 \
                 million triangles); render it with {alternative}, or use fewer triangles",
                mib(bytes as u64),
                scene.triangles.len(),
                mib(limit)
            ));
        }
    }
    Ok(())
}

impl Residency {
    /// Uniform buffers on CPU adapters (lavapipe, llvmpipe) when every array fits the device's
    /// uniform binding limit; storage buffers otherwise. Real GPUs get storage buffers: their
    /// uniform (constant) caches serialise divergent indices, which BVH traversal has.
    pub fn preferred(info: &wgpu::AdapterInfo, limits: &wgpu::Limits, scene: &FlatScene) -> Self {
        let max = limits.max_uniform_buffer_binding_size as usize;
        if info.device_type == wgpu::DeviceType::Cpu
            && scene_arrays(scene).iter().all(|&(_, s)| s <= max)
        {
            Residency::Uniform
        } else {
            Residency::Storage
        }
    }
}

/// Rows per film band of the methods that splat: as many as keep the tallies (a splat cell and
/// a path head per pixel), the pass sums and the camera radiance of the band each within one
/// binding of `limit` bytes; the whole image if it fits, None if not even one row does.
pub fn splat_band_rows(limit: u64, width: u32, height: u32) -> Option<u32> {
    let fixed = 4 * tally_words(0);
    let per_pixel = (4 * (tally_words(1) - tally_words(0)))
        .max(std::mem::size_of::<PixelSums>() as u64)
        .max(16);
    let rows = limit.saturating_sub(fixed) / (per_pixel * width as u64);
    (rows > 0).then(|| rows.min(height as u64) as u32)
}
