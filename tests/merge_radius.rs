//! The merge radius follows what the camera sees (`hexray::transport::merging`, "What sets the
//! radius"): geometry that the camera never sees leaves vcm's image as it was, and a scene
//! scaled by any factor renders the same image. Each comparison is of two independent renders
//! (other seeds) by their iterations' batch means (`parity_of_iterations`), and each is shown
//! to reject a radius that does not follow the view.

use crate::common::parity::{parity_of_iterations, Parity};
use crate::common::*;
use hexray::scene::{Scene, SceneDesc};
use hexray::transport::merging::{scene_radius, MergeRadius, DEFAULT_ALPHA};
use hexray::transport::method::Method;

const ROOM: &str = "scenes/tncg15_room.json";

/// tncg15_room with a diffuse ground quad 10,000 units wide, 100 units below the room's floor:
/// the camera never sees it, and the closed room keeps every light subpath from it.
const GROUND: &str = "scenes/stability/unseen_ground.json";

/// Image side and iterations of every render here.
const SIZE: u32 = 32;
const ITERATIONS: u32 = 64;

/// vcm's iterations of `scene` on `backend` at `radius` (None: the default).
fn iterations(
    render: Render<'_>,
    backend: Backend,
    seed: u32,
    radius: Option<MergeRadius>,
) -> Vec<hexray::film::Film> {
    let render = render
        .size(SIZE, SIZE)
        .spp(ITERATIONS)
        .seed(seed)
        .method(Method::Vcm);
    match radius {
        Some(r) => render.radius(r).iterations_on(backend),
        None => render.iterations_on(backend),
    }
}

/// A scene-bound radius, the baseline the view's radius is compared with: 0.03 of the scene's
/// bounding-sphere radius at every vertex.
fn scene_bound_radius(scene: &Scene) -> MergeRadius {
    let flat = hexray::layout::FlatScene::build(scene, hexray::render::CpuBackend::TRAVERSAL);
    MergeRadius::uniform(0.03 * scene_radius(&flat), DEFAULT_ALPHA)
}

/// The room against the room with the unseen ground, each at the radius `radius_of` gives it.
fn ground_parity(backend: Backend, radius_of: impl Fn(&Scene) -> Option<MergeRadius>) -> Parity {
    let (room, _) = load(ROOM);
    let (ground, _) = load(GROUND);
    let a = iterations(Render::scene(&room), backend, 41, radius_of(&room));
    let b = iterations(Render::scene(&ground), backend, 42, radius_of(&ground));
    let p = parity_of_iterations(&a, &b);
    eprintln!("tncg15_room against it with an unseen ground ({backend:?}): {p}");
    p
}

on_each_backend! {
    /// vcm's image of tncg15_room is the same with a ground plane that the camera never sees.
    fn an_unseen_ground_plane_leaves_the_vcm_image_unchanged(backend) {
        let p = ground_parity(backend, |_| None);
        assert!(p.same(), "{p}");
    }

    /// vcm's image of tncg15_room scaled by 10^-2 and by 10^3 is the image at scale 1: the
    /// radius scales with the view.
    fn a_scaled_scene_renders_the_same_vcm_image(backend) {
        let (room, _) = load(ROOM);
        let a = iterations(Render::scene(&room), backend, 43, None);
        for (k, factor) in [1e-2, 1e3].into_iter().enumerate() {
            let scaled = load_changed(ROOM, |desc| scale(desc, factor));
            let b = iterations(Render::scene(&scaled), backend, 44 + k as u32, None);
            let p = parity_of_iterations(&a, &b);
            eprintln!("tncg15_room against it scaled by {factor} ({backend:?}): {p}");
            assert!(p.same(), "scaled by {factor}: {p}");
        }
    }
}

/// The ground-plane comparison has power: at the radius of the scene's bounds (0.03 of its
/// bounding-sphere radius: 0.335 in the room, 212 with the ground) the two images differ.
#[test]
fn the_ground_plane_check_rejects_the_scene_bound_radius() {
    let p = ground_parity(Backend::Cpu, |scene| Some(scene_bound_radius(scene)));
    assert!(!p.same(), "{p}");
}

/// The scale comparison has power: the largest radius of the scene at scale 1, kept in scene
/// units at every vertex of the scene scaled by 10^-2 (a disk 100 times as wide against the
/// room), changes the image.
#[test]
fn the_scale_check_rejects_a_radius_in_fixed_units() {
    let (room, _) = load(ROOM);
    let at_one = MergeRadius::uniform(default_radius(ROOM, Method::Vcm).initial, DEFAULT_ALPHA);
    let a = iterations(Render::scene(&room), Backend::Cpu, 43, None);
    let scaled = load_changed(ROOM, |desc| scale(desc, 1e-2));
    let b = iterations(Render::scene(&scaled), Backend::Cpu, 44, Some(at_one));
    let p = parity_of_iterations(&a, &b);
    eprintln!("tncg15_room against it scaled by 1e-2 at the radius of scale 1: {p}");
    assert!(!p.same(), "{p}");
}

/// The scene scaled by `factor` about the origin: its geometry and its camera.
fn scale(desc: &mut SceneDesc, factor: f64) {
    assert!(desc.boxes.is_empty() && desc.meshes.is_empty());
    let s = |p: &mut [f64; 3]| p.iter_mut().for_each(|c| *c *= factor);
    for t in &mut desc.triangles {
        t.v.iter_mut().for_each(s);
    }
    for sphere in &mut desc.spheres {
        s(&mut sphere.center);
        sphere.radius *= factor;
    }
    s(&mut desc.camera.eye);
    s(&mut desc.camera.look_at);
}
