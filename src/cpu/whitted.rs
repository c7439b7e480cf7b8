//! Whitted ray tracing (Whitted 1980), where both TNCG15 reports begin: the light that reaches
//! each diffuse surface the camera sees straight from the emitters, and perfect reflection and
//! refraction at mirrors and glass, both followed where glass splits a ray. Nothing else: no
//! indirect diffuse light, and no light that reaches a diffuse surface by way of a mirror or
//! glass (caustics). The image is biased by exactly that light; the standard error covers the
//! noise of the pixel and emitter samples only.
//!
//! `shaders/whitted.wgsl` is this function again, with the same names, the same steps in the same
//! order and the same step comments.
//!
//! The estimate of one camera sample is a sum over a tree of rays: the camera ray, and at each
//! mirror its reflection, at each glass surface its reflection weighted by the Fresnel factor F
//! and its refraction weighted by 1 - F (and by 1/η² for radiance crossing the boundary,
//! pbrt-v4 eq. 9.17), to at most [`WHITTED_MAX_DEPTH`] specular bounces. The tree is walked depth
//! first with a stack of [`WHITTED_MAX_DEPTH`] + 1 branches, the refraction before the
//! reflection, in the same order on both backends. Each diffuse hit takes one point on the
//! emitters, chosen as path tracing's next-event estimation chooses it (an emitter by power, a
//! uniform point on it), so that each sample's direct light is an unbiased estimate of the
//! direct light; the random numbers are those of the branch's index in the walk
//! (`dim_light(branch)`), so the branches of one sample draw different points. Apart from the
//! point in the pixel and those emitter points, the method is deterministic.

use crate::accel::bvh::{intersect_closest, occluded};
use crate::layout::{FlatScene, KIND_EMITTER, KIND_GLASS, KIND_MIRROR};
use crate::math::geometry::{offset_ray_origin, Ray};
use crate::math::sampling::{dim_light, Sampler, DIM_CAMERA};
use crate::transport::bsdf::{fresnel_dielectric, is_diffuse, reflect, refract};
use crate::transport::camera::Camera;
use crate::transport::faults::Faults;
use crate::transport::light::{link_to_emitter, sample_emitter};
use arrayvec::ArrayVec;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// The most specular bounces a branch follows: a glass sphere's ray tree then has at most
/// 2^6 - 1 = 63 branches. pbrt-v3's Whitted integrator defaults to 5 too.
pub const WHITTED_MAX_DEPTH: u32 = 5;

/// One ray of the tree: where it goes, what it carries (the product of the specular weights
/// before it) and how many specular bounces led to it.
#[derive(Clone, Copy, Debug)]
struct Branch {
    ray: Ray,
    weight: Vec3,
    depth: u32,
}

/// The radiance arriving at pixel (x, y) along one camera sample's ray tree. `rays` counts the
/// rays traced (closest-hit and shadow), for the benchmark's rays/s.
pub fn trace_whitted(
    scene: &FlatScene,
    camera: &Camera,
    x: u32,
    y: u32,
    sampler: &Sampler,
    faults: Faults,
    rays: &mut u64,
) -> Vec3 {
    // Step 1 - camera ray: a uniform point in the pixel (box filter) through the pinhole, as
    // path tracing's.
    let u_camera = sampler.draw4(DIM_CAMERA);
    let mut stack = ArrayVec::<Branch, { WHITTED_MAX_DEPTH as usize + 1 }>::new();
    stack.push(Branch {
        ray: camera.ray(x, y, u_camera[0], u_camera[1]),
        weight: Vec3::ONE,
        depth: 0,
    });
    let mut radiance = Vec3::ZERO;
    let mut branch = 0u32;
    while let Some(b) = stack.pop() {
        let index = branch;
        branch += 1;

        // Step 2 - closest hit: the nearest surface along the ray over the BVH; a miss sees
        // nothing.
        *rays += 1;
        let Some(hit) = intersect_closest(scene, &b.ray, f32::MAX) else {
            continue;
        };
        let material = scene.materials[hit.material as usize];
        let wo = -b.ray.d;
        let cos_o = hit.n.dot(wo);

        // Step 3 - emission: an emitter seen from its front, straight or in mirrors and glass.
        if material.kind == KIND_EMITTER && cos_o > 0.0 {
            radiance += b.weight * Vec3::from(material.emission);
        }

        // Step 4 - direct light at diffuse surfaces: one point on the emitters (an emitter by
        // power, a uniform point on it), one shadow ray, and f · Le · cos θs / p_ω, with p_ω the
        // point's area pdf converted to solid angle. The branch ends here.
        if is_diffuse(&material) {
            let u = sampler.draw4(dim_light(index));
            let n_facing = if cos_o < 0.0 { -hit.n } else { hit.n };
            let ls = sample_emitter(scene, u[0], u[1], u[2]);
            if let Some(link) = link_to_emitter(hit.p, hit.p_err, hit.n, n_facing, &ls) {
                *rays += 1;
                if !occluded(scene, &link.shadow, 1.0) {
                    let f = Vec3::from(material.color) * FRAC_1_PI;
                    radiance += b.weight * f * link.le * (link.cos_s / link.light_pdf);
                }
            }
            continue;
        }

        // Step 5 - perfect specular: a mirror reflects with its reflectance; glass reflects
        // with F and refracts with (1 - F) · tint / η², both followed (the refraction first),
        // up to WHITTED_MAX_DEPTH bounces. A black emitter ends the branch.
        if b.depth >= WHITTED_MAX_DEPTH {
            continue;
        }
        let weight = b.weight * faults.specular_scale;
        let mut follow = |wi: Vec3, w: Vec3| {
            if w.max_element() > 0.0 {
                stack.push(Branch {
                    ray: Ray {
                        o: offset_ray_origin(hit.p, hit.p_err, hit.n, wi),
                        d: wi,
                    },
                    weight: w,
                    depth: b.depth + 1,
                });
            }
        };
        if material.kind == KIND_MIRROR {
            follow(reflect(wo, hit.n), weight * Vec3::from(material.color));
        } else if material.kind == KIND_GLASS {
            let f = fresnel_dielectric(cos_o, material.ior);
            follow(reflect(wo, hit.n), weight * f);
            if let Some((wt, etap)) = refract(wo, hit.n, material.ior) {
                let tint = Vec3::from(material.color);
                follow(wt, weight * (1.0 - f) * tint / (etap * etap));
            }
        }
    }
    radiance
}
