//! A ray tangent to a mirror sphere: a grazing hit whose cosine squared is 0 in f32, where the
//! bidirectional methods' MIS quantities would divide by zero (glass_room, vcm, seed 3 meets one
//! in ten million samples: a camera subpath tangent to a sphere at cos θ = 0).
//!
//! `scenes/stability/grazing.json` (a closed enclosure whose upper half emits) with a mirror
//! sphere of radius 0.5 centred at (2, 0, 1.25), seen from (0, 0, 1.75) along +x with a field of
//! view of 1e-28 degrees: every camera ray is (1, ±1e-30, ±1e-30), tangent to the sphere's top
//! at (2, 0, 1.75), where |cos θ| ≈ 1e-30 and its square underflows to 0. These rays are a set
//! of measure zero; the methods end a subpath at a hit whose area density vanishes in f32
//! (`subpath::density_vanishes`), which changes no estimate an f32 can resolve (its doc says
//! why). The property is deterministic: every sample of bdpt, vcm and sppm is finite (no sample
//! dropped), on both backends. The test first checks, with the renderer's own intersection,
//! that the camera's rays really meet the sphere at such a cosine, so that it cannot pass by
//! missing the case. Power: with `Faults::continue_at_vanishing_density` the subpath goes on
//! past the tangent hit, and every bdpt and vcm sample of the lower half of the image is NaN
//! (32 of 64).

use crate::common::*;
use hexray::accel::bvh::intersect_closest;
use hexray::layout::FlatScene;
use hexray::scene::{MaterialDesc, Scene, SceneDesc, SphereDesc};
use hexray::transport::camera::Camera;
use hexray::transport::faults::Faults;
use hexray::transport::method::Method;
use hexray::transport::subpath::density_vanishes;

const SCENE: &str = "scenes/stability/grazing.json";
const SIZE: u32 = 4;
const ITERATIONS: u32 = 4;

const CONTINUE: Faults = Faults {
    continue_at_vanishing_density: true,
    ..Faults::NONE
};

fn tangent_view(d: &mut SceneDesc) {
    d.materials.insert(
        "mirror".into(),
        MaterialDesc::Mirror {
            reflectance: [1.0; 3],
        },
    );
    d.spheres.push(SphereDesc {
        center: [2.0, 0.0, 1.25],
        radius: 0.5,
        material: "mirror".into(),
        flip_normals: false,
    });
    d.camera.eye = [0.0, 0.0, 1.75];
    d.camera.look_at = [1.0, 0.0, 1.75];
    d.camera.up = [0.0, 0.0, 1.0];
    d.camera.vfov_deg = 1e-28;
}

fn scene() -> Scene {
    load_changed(SCENE, tangent_view)
}

/// The precondition: each pixel's rays (centre and corners) meet the mirror sphere first, at a
/// cosine whose density vanishes.
fn assert_every_ray_is_tangent(scene: &Scene) {
    let flat = FlatScene::build(scene, hexray::render::CpuBackend::TRAVERSAL);
    let camera = Camera::new(&scene.desc.camera, SIZE, SIZE);
    for y in 0..SIZE {
        for x in 0..SIZE {
            for (jx, jy) in [
                (0.5, 0.5),
                (0.0, 0.0),
                (0.999, 0.0),
                (0.0, 0.999),
                (0.999, 0.999),
            ] {
                let ray = camera.ray(x, y, jx, jy);
                let hit = intersect_closest(&flat, &ray, f32::MAX)
                    .unwrap_or_else(|| panic!("pixel ({x}, {y}) ray {ray:?} misses"));
                let material = flat.materials[hit.material as usize];
                let cos = hit.n.dot(-ray.d);
                assert!(
                    material.kind == hexray::layout::KIND_MIRROR && density_vanishes(cos),
                    "pixel ({x}, {y}): ray {ray:?} meets material kind {} at cos {cos:e}",
                    material.kind
                );
            }
        }
    }
}

/// The dropped samples of each method on `backend`, seeds 90, 91, 92.
fn dropped_per_method(backend: Backend, faults: Faults) -> Vec<(Method, u64)> {
    let scene = scene();
    assert_every_ray_is_tangent(&scene);
    [Method::Bdpt, Method::Vcm, Method::Sppm]
        .into_iter()
        .enumerate()
        .map(|(i, method)| {
            let film = Render::scene(&scene)
                .size(SIZE, SIZE)
                .spp(ITERATIONS)
                .seed(90 + i as u32)
                .method(method)
                .faults(faults)
                .on(backend);
            assert_eq!(film.spp(), ITERATIONS as u64, "{method:?}");
            (method, film.dropped())
        })
        .collect()
}

fn assert_all_finite(backend: Backend, dropped: &[(Method, u64)]) {
    eprintln!("{backend}: dropped samples per method {dropped:?}");
    assert!(
        dropped.iter().all(|&(_, n)| n == 0),
        "{backend}: samples dropped on rays tangent to a mirror sphere: {dropped:?}"
    );
}

/// The planted fault seen: every bdpt and vcm sample of the lower half of the image is NaN.
/// (Its rays, going down by 1e-30, reflect off the sphere onto the emitting wall, whose
/// emission is weighed with the NaN quantities; the upper half's rays, going up by 1e-30, come
/// to nothing with or without the fault, and sppm, whose weights are 1, never reads them.)
fn assert_connecting_samples_dropped(backend: Backend, dropped: &[(Method, u64)]) {
    eprintln!("{backend}, subpaths continued past the tangent hit: dropped {dropped:?}");
    let lower_half = (SIZE * SIZE / 2 * ITERATIONS) as u64;
    for &(method, n) in dropped {
        if method != Method::Sppm {
            assert!(
                n >= lower_half,
                "{backend}: {method:?} dropped {n} samples, not the {lower_half} planted NaNs"
            );
        }
    }
}

on_each_backend! {
    fn subpaths_tangent_to_a_mirror_sphere_give_finite_samples(backend) {
        assert_all_finite(backend, &dropped_per_method(backend, Faults::NONE));
    }

    fn subpaths_continued_past_a_tangent_hit_are_rejected(backend) {
        assert_connecting_samples_dropped(backend, &dropped_per_method(backend, CONTINUE));
    }
}
