//! The safety net (`hexray::cpu::dark_image`): an image that is nearly black where the scene's
//! light reaches the camera is warned of, whatever the method, and an image that shows the
//! light is not.

use crate::common::*;
use hexray::cpu::dark_image::dark_image_warning;
use hexray::transport::camera::Camera;
use hexray::transport::method::Method;
use std::process::Command;

/// tncg15_room with a far emitter facing away from it that holds nearly all of the scene's
/// power (`scenes/stability/make_stability_d.py`): light tracing, which picks emitters by power,
/// nearly always starts from it, and its image is nearly black.
const FAR_EMITTER: &str = "scenes/stability/far_emitter.json";
const ROOM: &str = "scenes/tncg15_room.json";

/// The warning for `method`'s 32x32 render of `rel` on `backend`, 8 iterations.
fn warning(rel: &str, method: Method, backend: Backend) -> Option<String> {
    let (scene, flat) = load(rel);
    let film = Render::file(rel)
        .size(32, 32)
        .spp(8)
        .seed(3)
        .method(method)
        .on(backend);
    let camera = Camera::new(&scene.desc.camera, 32, 32);
    dark_image_warning(&flat, &camera, method, film.image_mean().0)
}

on_each_backend! {
    /// Light tracing of the far-emitter scene misses the room's light: warned of.
    fn an_image_that_misses_the_light_is_warned_of(backend) {
        let w = warning(FAR_EMITTER, Method::Light, backend);
        assert!(w.is_some(), "no warning");
    }

    /// Light tracing of tncg15_room shows the room (not its mirrors): no warning, so the check
    /// can pass.
    fn an_image_that_shows_the_light_is_not_warned_of(backend) {
        let w = warning(ROOM, Method::Light, backend);
        assert!(w.is_none(), "{w:?}");
    }
}

/// The warning reaches the user: `hexray render` prints it, and still writes the image and
/// exits 0 (the method renders what it says it renders).
#[test]
fn render_prints_the_warning() {
    let dir = temp_dir!("dark");
    let exr = dir.join("d.exr");
    let o = Command::new(hexray_bin())
        .args([
            "render",
            FAR_EMITTER,
            "--backend",
            "cpu",
            "--method",
            "light",
        ])
        .args([
            "--width", "32", "--height", "32", "--spp", "8", "-q", "--out",
        ])
        .arg(&exr)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("warning: the image is nearly black"),
        "{stderr}"
    );
    assert!(exr.exists());
}
