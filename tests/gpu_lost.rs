//! A lost device ends the render with the samples taken so far: passes completed before the
//! loss stay in the film, and the pass that meets the loss returns an error instead of
//! corrupting it. The loss is provoked with `Device::destroy` on a device of the test's own.

use crate::common::{gpu, load};
use hexray::film::Film;
use hexray::gpu::{Checks, GpuRenderer, Residency};
use hexray::render::GpuBackend;
use hexray::render::{render_progressive, Backend, Budget, StopReason};
use hexray::transport::camera::Camera;
use hexray::transport::faults::Faults;
use std::sync::atomic::AtomicBool;

/// Destroys the device after its first pass.
struct Fragile {
    inner: GpuBackend,
    device: wgpu::Device,
    passes: u32,
}

impl Backend for Fragile {
    fn name(&self) -> &'static str {
        "gpu"
    }
    fn device(&self) -> String {
        self.inner.device()
    }
    fn pass_until(
        &mut self,
        first: u32,
        count: u32,
        film: &mut Film,
        stop: &AtomicBool,
    ) -> anyhow::Result<()> {
        if self.passes == 1 {
            self.device.destroy();
        }
        self.passes += 1;
        self.inner.pass_until(first, count, film, stop)
    }
}

#[test]
fn a_lost_device_keeps_the_samples_taken_before() {
    if gpu().is_none() {
        return;
    }
    let own = hexray::gpu::acquire(None).unwrap();
    let (scene, flat) = load("scenes/cornell_box.json");
    let camera = Camera::new(&scene.desc.camera, 16, 16);
    let renderer = GpuRenderer::new(
        &own.device,
        &own.queue,
        &flat,
        camera,
        1,
        Faults::NONE,
        Checks::Unchecked,
        Residency::Storage,
        hexray::transport::method::Method::Path,
        0.0,
        None,
    )
    .unwrap();
    let mut backend = Fragile {
        inner: GpuBackend {
            renderer,
            adapter: own.info.name.clone(),
        },
        device: own.device.clone(),
        passes: 0,
    };
    let mut film = Film::new(16, 16);
    let budget = Budget {
        spp: Some(100),
        ..Budget::default()
    };
    let report = render_progressive(
        &mut backend,
        &mut film,
        budget,
        &AtomicBool::new(false),
        |_, _, _| {},
    );
    let StopReason::Failed(why) = &report.reason else {
        panic!("the render did not fail: {:?}", report.reason);
    };
    eprintln!("render ended: {why}");
    // The first pass (1 spp) survived, whole, in every pixel.
    assert_eq!(report.spp, 1);
    assert!(film.pixels.iter().all(|p| p.n + p.dropped == 1));
}
