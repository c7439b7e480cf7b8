//! The path integrator: one camera sample's radiance estimate, as an iterative loop.
//!
//! `shaders/path.wgsl` is this function again, with the same names, the same steps in the same
//! order and the same step comments; read the two side by side. One difference of schedule: the
//! shader traces step 4's shadow ray where it is made, while here `shade_hit` hands it out
//! ([`NextEvent`]) so that the wavefront (`path_wavefront.rs`) can trace a round's shadow rays
//! together; its light is added before the next bounce's, the same sum in the same order. The
//! wavefront keeps eight paths in SIMD lanes and shades their diffuse hits there with
//! `shade_hit`'s arithmetic, operation for operation, so each path is the same bit for bit.
//!
//! The estimator is unidirectional path tracing with next-event estimation and multiple
//! importance sampling (Veach's thesis, ch. 9): at each diffuse vertex, direct light is
//! estimated twice, once by sampling a point on an emitter and once by the BSDF-sampled
//! continuation ray hitting an emitter, and the two are combined with the power heuristic.
//! Specular vertices (mirror, glass) cannot be reached by light sampling, so emission found
//! after them is counted in full. Russian roulette ends paths without bias; there is no
//! maximum depth.

use crate::accel::bvh::{intersect_closest, occluded};
use crate::layout::{FlatScene, KIND_DIFFUSE, KIND_EMITTER};
use crate::math::geometry::{offset_ray_origin, Ray, SurfaceHit};
use crate::math::sampling::{
    dim_bsdf, dim_light, dim_light_extra, power_heuristic, Sampler, DIM_CAMERA, MAX_LIGHT_SAMPLES,
};
use crate::transport::bsdf::{sample_bsdf, BsdfSample, Transport};
use crate::transport::camera::Camera;
use crate::transport::faults::Faults;
use crate::transport::light::{
    area_to_solid_angle, emitter_pdf_area, link_to_emitter, sample_emitter,
};
use arrayvec::ArrayVec;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Russian roulette starts at this bounce. The first bounces carry most of the image's energy
/// and end few paths anyway, so rouletting them adds variance for little saved time; Mitsuba
/// uses 5 and pbrt-v4 1, and 3 sits between.
pub const RR_START_BOUNCE: u32 = 3;
/// The survival probability is capped below 1 so that even paths of unit throughput (mirror
/// corridors, white furnaces) end with probability 1.
pub const RR_MAX_SURVIVAL: f32 = 0.95;

/// The radiance arriving at pixel (x, y) along one camera sample's path, with `light_samples`
/// shadow rays at every diffuse vertex (1 is the default, at most `MAX_LIGHT_SAMPLES`; see
/// step 4). `rays` counts the rays traced (closest-hit and shadow), for the benchmark's rays/s.
///
/// The path is started ([`start_path`]), advanced one bounce at a time ([`path_bounce`]) until
/// it ends, and finished ([`finish_path`]). `path_wavefront::trace_pixels` runs the same steps for many
/// pixels at once, their rays in packets; the shader's `render_pass` hands a lane whose path ended
/// to the pixel's next sample at once (path regeneration), so that lanes running in lockstep do
/// not wait for their group's longest path.
#[allow(clippy::too_many_arguments)]
pub fn trace_path(
    scene: &FlatScene,
    camera: &Camera,
    x: u32,
    y: u32,
    sampler: &Sampler,
    light_samples: u32,
    faults: Faults,
    rays: &mut u64,
) -> Vec3 {
    let mut path = start_path(camera, x, y, sampler);
    while path_bounce(scene, &mut path, sampler, light_samples, faults, rays) {}
    finish_path(&path)
}

/// One camera sample's path between two bounces: the ray to trace next and what the path has
/// gathered and carries so far.
#[derive(Clone, Copy, Debug)]
pub struct PathState {
    pub ray: Ray,
    pub radiance: Vec3,
    pub throughput: Vec3,
    /// Product of etap² over refractions; throughput x eta_scale is what roulette looks at, so
    /// that radiance scaling at glass boundaries does not end paths inside glass.
    pub eta_scale: f32,
    /// Solid-angle pdf of the BSDF sample that produced `ray`; 0 for the camera ray and after a
    /// specular bounce (no light-sampling strategy competes there).
    pub bsdf_pdf: f32,
    pub bounce: u32,
    /// `Faults::grey_indirect` only: the radiance gathered before the first diffuse bounce, or
    /// None until that bounce.
    pub before_indirect: Option<Vec3>,
}

/// Step 1 - camera ray: a uniform point in the pixel (box filter) through the pinhole.
#[inline]
pub fn start_path(camera: &Camera, x: u32, y: u32, sampler: &Sampler) -> PathState {
    let u_camera = sampler.draw4(DIM_CAMERA);
    PathState {
        ray: camera.ray(x, y, u_camera[0], u_camera[1]),
        radiance: Vec3::ZERO,
        throughput: Vec3::ONE,
        eta_scale: 1.0,
        bsdf_pdf: 0.0,
        bounce: 0,
        before_indirect: None,
    }
}

/// Steps 2 to 6 of one bounce: traces `path.ray`, adds what it finds to `path.radiance` and
/// prepares the next ray; false when the path has ended.
#[inline]
pub fn path_bounce(
    scene: &FlatScene,
    path: &mut PathState,
    sampler: &Sampler,
    light_samples: u32,
    faults: Faults,
    rays: &mut u64,
) -> bool {
    // Step 2 - closest hit: the nearest surface along the ray over the BVH; nothing is
    // outside the scene, so a miss ends the path.
    *rays += 1;
    let Some(hit) = intersect_closest(scene, &path.ray, f32::MAX) else {
        return false;
    };
    // Step 4's shadow rays, at most MAX_LIGHT_SAMPLES, on the stack.
    let mut events = ArrayVec::<NextEvent, { MAX_LIGHT_SAMPLES as usize }>::new();
    let going_on = shade_hit(
        scene,
        path,
        &hit,
        sampler,
        light_samples,
        faults,
        &mut events,
    );
    for event in &events {
        *rays += 1;
        add_next_event(path, event, !occluded(scene, &event.ray, 1.0));
    }
    end_bounce(path, faults);
    going_on
}

/// A shadow ray of next-event estimation (step 4) and the radiance it adds to its path where
/// nothing blocks it.
#[derive(Clone, Copy, Debug)]
pub struct NextEvent {
    pub ray: Ray,
    pub value: Vec3,
}

/// Steps 3 to 6 at the hit of `path.ray`: adds emission, pushes step 4's shadow rays to
/// `events` (their light is added by [`add_next_event`], in order, once traced) and prepares the
/// next ray; false when the path has ended.
#[inline]
pub fn shade_hit(
    scene: &FlatScene,
    path: &mut PathState,
    hit: &SurfaceHit,
    sampler: &Sampler,
    light_samples: u32,
    faults: Faults,
    events: &mut impl Extend<NextEvent>,
) -> bool {
    // N light samples and one BSDF sample per vertex: Veach's multi-sample MIS weighs each
    // strategy by n_i · p_i (eq. 9.13), so N enters both weights and divides the NEE sum.
    let n_light = light_samples.max(1) as f32;
    let bounce = path.bounce;
    let material = scene.materials[hit.material as usize];
    let wo = -path.ray.d;
    let cos_o = hit.n.dot(wo);

    // Step 3 - emission: an emitter seen from its front. After the camera or a specular
    // bounce it is counted in full; after a diffuse bounce it is weighted by the power
    // heuristic against light sampling, whose pdf for this point is converted to solid
    // angle at the previous vertex (the ray's direction is unit, so hit.t is the distance).
    if material.kind == KIND_EMITTER && cos_o > 0.0 {
        let le = Vec3::from(material.emission);
        if path.bsdf_pdf == 0.0 {
            path.radiance += path.throughput * le;
        } else {
            let light_pdf =
                area_to_solid_angle(emitter_pdf_area(scene, hit.prim), hit.t * hit.t, cos_o);
            path.radiance +=
                path.throughput * le * power_heuristic(path.bsdf_pdf, n_light * light_pdf);
        }
    }

    // Step 4 - next-event estimation at diffuse surfaces: N times, choose an emitter
    // triangle by power and a uniform point on it, trace one shadow ray, and add
    // f · Le · cos θs / (N · p_ω(light)), with p_ω the area pdf converted to solid angle,
    // weighted by the power heuristic against BSDF sampling (p_ω(bsdf) = cos θs / pi).
    let u_light = sampler.draw4(dim_light(bounce));
    let albedo = Vec3::from(material.color);
    let diffuse = material.kind == KIND_DIFFUSE
        || (material.kind == KIND_EMITTER && albedo.max_element() > 0.0);
    if material.kind == KIND_EMITTER && !diffuse {
        // A black emitter reflects nothing: the path ends here.
        return false;
    }
    if diffuse {
        let n_facing = if cos_o < 0.0 { -hit.n } else { hit.n };
        for j in 0..light_samples.max(1) {
            let u = if j == 0 {
                u_light
            } else {
                sampler.draw4(dim_light_extra(bounce, j))
            };
            let ls = sample_emitter(scene, u[0], u[1], u[2]);
            if let Some(link) = link_to_emitter(hit.p, hit.p_err, hit.n, n_facing, &ls) {
                let (cos_s, light_pdf) = (link.cos_s, link.light_pdf);
                let f = albedo * FRAC_1_PI;
                let w = power_heuristic(n_light * light_pdf, cos_s * FRAC_1_PI);
                events.extend([NextEvent {
                    ray: link.shadow,
                    value: path.throughput * f * link.le * (cos_s * w / (n_light * light_pdf)),
                }]);
            }
        }
    }

    // Step 5 - scattering: sample the BSDF for the next direction; the throughput takes
    // the sample's weight f · |cos θi| / pdf.
    let u_bsdf = sampler.draw4(dim_bsdf(bounce));
    let bs = sample_bsdf(&material, hit.n, wo, u_bsdf, Transport::Radiance);
    take_bsdf_sample(
        path,
        &bs,
        || offset_ray_origin(hit.p, hit.p_err, hit.n, bs.wi),
        u_light[3],
        faults,
    )
}

/// The end of step 5 and step 6, once the BSDF sample `bs` is drawn: the throughput takes its
/// weight and the next ray leaves `origin()` along it, then roulette with `u_roulette`; false
/// when the path has ended.
#[inline]
fn take_bsdf_sample(
    path: &mut PathState,
    bs: &BsdfSample,
    origin: impl FnOnce() -> Vec3,
    u_roulette: f32,
    faults: Faults,
) -> bool {
    path.throughput *= bs.weight;
    if bs.pdf == 0.0 {
        path.throughput *= faults.specular_scale;
    }
    path.eta_scale *= bs.eta2;
    path.bsdf_pdf = bs.pdf;
    if path.throughput.max_element() <= 0.0 {
        return false;
    }
    path.ray.o = origin();
    path.ray.d = bs.wi;

    // Step 6 - Russian roulette: from bounce RR_START_BOUNCE on, continue with probability
    // q = min(max(throughput) · eta_scale, 0.95) and divide by q, which keeps the estimator
    // unbiased (E[X / q · 1{u < q}] = E[X]) while ending low-throughput paths.
    if path.bounce >= RR_START_BOUNCE {
        let q = (path.throughput.max_element() * path.eta_scale).min(RR_MAX_SURVIVAL);
        if u_roulette >= q {
            return false;
        }
        path.throughput /= q;
    }
    path.bounce += 1;
    path.bounce < faults.max_bounces
}

/// Step 4's light, once its shadow ray is traced: added where the ray was `clear`.
#[inline]
pub fn add_next_event(path: &mut PathState, event: &NextEvent, clear: bool) {
    if clear {
        path.radiance += event.value;
    }
}

/// The end of a bounce, once its next-event light is in: under `Faults::grey_indirect`, the
/// radiance gathered up to the first diffuse bounce is kept. (`bsdf_pdf` is that of the BSDF
/// sample this bounce took, or, where the path ended before step 5, of an earlier one, which
/// was positive only if the snapshot was taken then.)
#[inline]
pub fn end_bounce(path: &mut PathState, faults: Faults) {
    if faults.grey_indirect && path.bsdf_pdf > 0.0 && path.before_indirect.is_none() {
        path.before_indirect = Some(path.radiance);
    }
}

/// The path's estimate; under `Faults::grey_indirect`, its indirect light replaced by its grey.
#[inline]
pub fn finish_path(path: &PathState) -> Vec3 {
    match path.before_indirect {
        Some(before) => {
            let indirect = path.radiance - before;
            before + Vec3::splat((indirect.x + indirect.y + indirect.z) / 3.0)
        }
        None => path.radiance,
    }
}
