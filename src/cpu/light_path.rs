//! The light pass of light tracing and BDPT: one light subpath, traced from an emitter, each of
//! its non-specular vertices (the light point included) connected to the pinhole camera and
//! splatted into the pixel that sees it (the strategies with t = 1), and, for BDPT, stored for
//! the camera pass to connect to. For BDPT, a subpath whose first hit is a planar mirror
//! ends at the diffuse vertex after it: every path through that vertex is next-event estimation's
//! through the mirror (`crate::transport::planar_mirror`).
//!
//! `shaders/light_path.wgsl` is this function again, with the same names, steps and step
//! comments.
//!
//! Light tracing alone (`--method light`) is this pass with every splat weighted 1: an unbiased
//! estimate of everything the camera sees on non-specular surfaces, and nothing of what it sees
//! through a mirror or glass (a light subpath can never be connected to the camera through a
//! specular bounce; those surfaces stay black). For BDPT and VCM the splats carry their MIS weights
//! against every other strategy (`crate::transport::subpath`), and the vertices are stored for the
//! camera pass to connect to and (VCM, SPPM) merge with; SPPM only stores them.
//!
//! The light subpath carries flux (importance transport): it starts with α = Le / p_A at the
//! light point, and each bounce multiplies it by the adjoint BSDF's f · |cos| / pdf
//! (`Transport::Importance`: refraction does not scale it by 1/η²). A splat at a vertex y seen
//! in pixel j adds α · f(y) · W_j · |cos θ_y| / dist² / N: the measurement's importance W_j
//! times the geometry term to the camera, divided by the N light subpaths of an iteration
//! (Veach's thesis, section 10.2; pbrt-v4's `ConnectBDPT` with t = 1).

use crate::accel::bvh::intersect_closest;
use crate::accel::packet::occluded_all;
use crate::cpu::path::{RR_MAX_SURVIVAL, RR_START_BOUNCE};
use crate::layout::{FlatScene, KIND_EMITTER, PRIM_PADDING};
use crate::math::geometry::{offset_ray_origin, Ray};
use crate::math::sampling::{dim_light_bounce, dim_splat, Sampler, DIM_EMISSION, DIM_EMISSION_DIR};
use crate::transport::bsdf::{eval_diffuse, is_diffuse, sample_bsdf, Transport};
use crate::transport::camera::{Camera, Raster};
use crate::transport::faults::Faults;
use crate::transport::light::sample_emission;
use crate::transport::merging::{footprint_share, merge_share};
use crate::transport::planar_mirror::{starts_by_a_mirror, takes_mirror_light};
use crate::transport::splat::Splats;
use crate::transport::subpath::{
    density_vanishes, shadow_survival, weight_light_point_to_camera, weight_to_camera, LightVertex,
    MergeMis, SubpathMis, LIGHT_SUBPATH_RR_START_BOUNCE, NO_VERTEX,
};
use glam::Vec3;

/// What the light pass does with a subpath besides splatting it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightPassMode {
    /// Light tracing: splats weighted 1, nothing stored.
    LightTracing,
    /// BDPT and VCM: splats weighted by MIS, diffuse vertices stored (BDPT: but for a subpath
    /// whose first hit is a planar mirror, none from the diffuse vertex after it on:
    /// `planar_mirror`).
    Bidirectional,
    /// SPPM: diffuse vertices stored as photons, nothing splatted.
    PhotonMapping,
    /// Jensen's photon mapping (`photon-map`, `photon_map.rs`): diffuse vertices stored as
    /// photons but for the light's first hits (direct light, which next-event estimation takes),
    /// nothing splatted.
    CausticAndGlobal,
}

/// Everything one light pass shares.
pub struct LightPass<'a> {
    pub scene: &'a FlatScene,
    pub camera: &'a Camera,
    /// N: light subpaths per iteration (one per pixel).
    pub n_light_paths: u32,
    pub mode: LightPassMode,
    pub faults: Faults,
    /// n_c per pixel (`subpath::camera_subpaths`; BDPT's MIS weights of the splats).
    pub camera_subpaths: &'a [u32],
    /// τ of the Russian roulette on the splats' visibility rays (BDPT; 0 for light tracing).
    pub shadow_threshold: f32,
    /// Merging's constants in the MIS weights of this iteration (`MergeMis::NONE` but for VCM
    /// and SPPM).
    pub merge: MergeMis,
    /// Whether this iteration merges (a radius above 0: SPPM, VCM).
    pub merges: bool,
    /// The iteration's largest merge radius.
    pub radius: f32,
    /// The view's reach (`MergeRadius::reach`; 0: every vertex merges within `radius`).
    pub reach: f32,
    /// Whether merges at a vertex use its local radius (`merging::local_radius`).
    pub local_radius: bool,
}

/// A splat whose visibility ray has survived its roulette and waits to be traced: the CPU traces a
/// chunk's splat rays together, eight at a time in SIMD lanes
/// ([`crate::accel::packet::occluded_all`]: the rays of a chunk all end at the eye), and splats the
/// visible ones ([`add_splats`]). Splat sums do not depend on their order
/// (`crate::transport::splat`), so the image is bit for bit that of splatting each at once, as
/// `shaders/light_path.wgsl` does.
#[derive(Clone, Copy, Debug)]
pub struct PendingSplat {
    pub pixel: u32,
    /// The splat's value, already divided by its roulette's survival probability.
    pub value: Vec3,
    /// The visibility segment, from the offset surface point to the eye (t in (0, 1)).
    pub ray: Ray,
}

/// Traces the visibility rays of `pending` and adds each splat whose eye is visible into
/// `splats`.
pub fn add_splats(scene: &FlatScene, pending: &[PendingSplat], splats: &Splats) {
    let rays: Vec<Ray> = pending.iter().map(|p| p.ray).collect();
    let mut blocked = vec![false; rays.len()];
    occluded_all(scene, &rays, &mut blocked);
    for (p, &b) in pending.iter().zip(&blocked) {
        if !b {
            splats.add(p.pixel as usize, p.value);
        }
    }
}

/// The longest full path (in edges) that the `max_bounces` fault lets through: the camera ray,
/// that many bounces and the connection.
#[inline]
pub fn max_path_edges(faults: &Faults) -> u32 {
    faults.max_bounces.saturating_add(1)
}

impl LightPass<'_> {
    /// The camera's importance where it sees a point (with the test-only fault that drops one
    /// cos θ).
    #[inline]
    fn importance(&self, r: &Raster) -> f32 {
        if self.faults.importance_missing_cos {
            r.importance * r.dir.dot(Vec3::from(self.camera.forward))
        } else {
            r.importance
        }
    }

    /// Splats `value` into `pixel` if the surface point `p` (error bound `p_err`, normal `n`)
    /// sees the eye, tracing the visibility ray with probability `shadow_survival` of the
    /// value (drawing `u`) and dividing by it. The ray waits in `pending` to be traced with
    /// the others of its chunk ([`add_splats`]). Returns the rays it will trace.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn splat(
        &self,
        pending: &mut Vec<PendingSplat>,
        pixel: usize,
        p: Vec3,
        p_err: Vec3,
        n: Vec3,
        value: Vec3,
        u: f32,
    ) -> u64 {
        let q = shadow_survival(value, self.shadow_threshold);
        if u >= q {
            return 0;
        }
        let eye = Vec3::from(self.camera.eye);
        let origin = offset_ray_origin(p, p_err, n, eye - p);
        pending.push(PendingSplat {
            pixel: pixel as u32,
            value: value / q,
            ray: Ray {
                o: origin,
                d: eye - origin,
            },
        });
        1
    }

    /// Traces light subpath `path` of `sampler`: appends its connections to the camera to
    /// `pending`, for [`add_splats`] to splat where the eye is visible (not for SPPM), and, but
    /// for light tracing, appends its diffuse vertices to `vertices`, in order. Returns the
    /// number of rays traced, the pending splats' included.
    pub fn trace_light_path(
        &self,
        path: u32,
        sampler: &Sampler,
        pending: &mut Vec<PendingSplat>,
        vertices: &mut Vec<LightVertex>,
    ) -> u64 {
        let scene = self.scene;
        let n_paths = self.n_light_paths as f32;
        let stores = self.mode != LightPassMode::LightTracing;
        let splats_to_camera = matches!(
            self.mode,
            LightPassMode::LightTracing | LightPassMode::Bidirectional
        );
        // The light's first hits are direct light, which photon-map takes by next-event
        // estimation alone.
        let stores_first_hits = self.mode != LightPassMode::CausticAndGlobal;
        // Where roulette starts: earlier where camera vertices connect to this subpath's.
        let rr_start = if self.mode == LightPassMode::Bidirectional {
            LIGHT_SUBPATH_RR_START_BOUNCE
        } else {
            RR_START_BOUNCE
        };
        let mut rays = 0u64;

        // Step 1 - emission: an emitter point chosen by power, uniformly on its area, and a
        // cosine-distributed direction from its front.
        let emission = sample_emission(
            scene,
            sampler.draw4(DIM_EMISSION),
            sampler.draw4(DIM_EMISSION_DIR),
        );
        let light = emission.point;

        // Step 2 - the light point seen by the camera (s = 1, t = 1): Le / p_A times the
        // importance and the geometry term toward the eye, against the camera subpaths that
        // hit the emitter there (s = 0).
        if let Some(r) = self.camera.raster(light.p).filter(|_| splats_to_camera) {
            let cos_l = -light.n.dot(r.dir);
            if cos_l > 0.0 && 1 <= max_path_edges(&self.faults) {
                let pixel = (r.y * self.camera.width + r.x) as usize;
                // The measurement W |cos| / dist², which times n_c is also the camera's density
                // of the point.
                let g_camera = self.importance(&r) * cos_l / r.dist2;
                let w = match self.mode {
                    LightPassMode::LightTracing => 1.0,
                    _ => weight_light_point_to_camera(
                        g_camera * self.camera_subpaths[pixel] as f32,
                        n_paths,
                        light.pdf_area,
                    ),
                };
                let value = light.le / light.pdf_area * (g_camera * w / n_paths);
                let u = sampler.draw4(DIM_EMISSION)[3];
                rays += self.splat(pending, pixel, light.p, light.p_err, light.n, value, u);
            }
        }

        let mut throughput = light.le * (emission.cos / (light.pdf_area * emission.pdf_dir));
        // The product of the BSDF weights alone, which Russian roulette looks at (the emitted
        // radiance over densities in `throughput` is no survival probability).
        let mut scattered = Vec3::ONE;
        let mut mis =
            SubpathMis::light(light.pdf_area, emission.pdf_dir, emission.cos, &self.merge);
        let mut ray = Ray {
            o: offset_ray_origin(light.p, light.p_err, light.n, emission.dir),
            d: emission.dir,
        };
        let mut bounce = 0u32;
        // Next-event estimation through planar mirrors takes the paths whose light end is the
        // light point, a planar mirror and a diffuse vertex (BDPT; `planar_mirror`): the
        // primitive of this subpath's first hit tells.
        let through_mirrors = takes_mirror_light(
            self.mode == LightPassMode::Bidirectional,
            self.merges,
            scene,
        );
        let mut first_prim = PRIM_PADDING;

        loop {
            // Step 3 - closest hit; the quantities turn the direction's density into an area
            // density at the hit.
            rays += 1;
            let Some(hit) = intersect_closest(scene, &ray, f32::MAX) else {
                break;
            };
            let material = scene.materials[hit.material as usize];
            let wo = -ray.d;
            let cos_o = hit.n.dot(wo);
            if density_vanishes(cos_o) && !self.faults.continue_at_vanishing_density {
                // A grazing hit that no f32 density can describe ends the subpath.
                break;
            }
            mis.at_hit(hit.t * hit.t, cos_o.abs());
            let length = bounce + 1;
            if length >= max_path_edges(&self.faults) {
                break;
            }

            let diffuse = is_diffuse(&material);
            if material.kind == KIND_EMITTER && !diffuse {
                // A black emitter absorbs.
                break;
            }
            if length == 1 {
                first_prim = hit.prim;
            } else if length == 2
                && through_mirrors
                && !self.faults.mirror_light_twice
                && starts_by_a_mirror(scene, first_prim, diffuse)
            {
                // The light came to this diffuse vertex from a planar mirror: every path
                // through it is next-event estimation's through the mirror (weight 1), so
                // the subpath stores and splats nothing more.
                break;
            }
            if diffuse {
                let n_facing = if cos_o < 0.0 { -hit.n } else { hit.n };
                let albedo = Vec3::from(material.color);

                // Step 4 - store the vertex for the camera subpaths to connect to and merge
                // with (BDPT, VCM, SPPM, photon-map but for first hits).
                if stores && (length > 1 || stores_first_hits) {
                    vertices.push(LightVertex {
                        p: hit.p.into(),
                        p_err: hit.p_err.max_element(),
                        n: n_facing.into(),
                        material: hit.material,
                        wo: wo.into(),
                        length,
                        throughput: throughput.into(),
                        next: NO_VERTEX,
                        d_vcm: mis.d_vcm,
                        d_vc: mis.d_vc,
                        d_vm: mis.d_vm,
                        path,
                    });
                }

                // Step 5 - connect to the camera (t = 1): splat α f W |cos| / dist² / N into
                // the pixel that sees the vertex.
                if let Some(r) = self.camera.raster(hit.p).filter(|_| splats_to_camera) {
                    let bsdf = eval_diffuse(albedo, n_facing, wo, -r.dir);
                    if bsdf.pdf > 0.0 && length < max_path_edges(&self.faults) {
                        let pixel = (r.y * self.camera.width + r.x) as usize;
                        let g_camera = self.importance(&r) * bsdf.cos_i / r.dist2;
                        let w = match self.mode {
                            LightPassMode::LightTracing => 1.0,
                            _ => weight_to_camera(
                                &mis,
                                // A camera subpath's merge here would use this vertex's
                                // radius, by its distance from the eye (vcm: within its
                                // clearance).
                                &self.merge.within(merge_share(
                                    self.scene,
                                    hit.p,
                                    hit.prim,
                                    self.radius,
                                    footprint_share(r.dist2.sqrt(), self.reach),
                                    self.local_radius,
                                )),
                                g_camera * self.camera_subpaths[pixel] as f32,
                                n_paths,
                                bsdf.pdf_rev,
                            ),
                        };
                        let value = throughput * bsdf.f * (g_camera * w / n_paths);
                        let u = sampler.draw4(dim_splat(bounce))[0];
                        rays += self.splat(pending, pixel, hit.p, hit.p_err, hit.n, value, u);
                    }
                }
            }

            // Step 6 - scattering: sample the adjoint BSDF; the quantities take the new
            // direction's densities (a specular bounce leaves only its cosine).
            let u = sampler.draw4(dim_light_bounce(bounce));
            let bs = sample_bsdf(&material, hit.n, wo, u, Transport::Importance);
            let cos_out = hit.n.dot(bs.wi).abs();
            if bs.pdf == 0.0 {
                scattered *= bs.weight * self.faults.specular_scale;
                throughput *= bs.weight * self.faults.specular_scale;
                mis.after_specular(cos_out);
            } else {
                scattered *= bs.weight;
                throughput *= bs.weight;
                mis.after_diffuse(
                    cos_out,
                    bs.pdf,
                    cos_o.abs() * std::f32::consts::FRAC_1_PI,
                    &self.merge,
                );
            }
            if scattered.max_element() <= 0.0 {
                break;
            }
            ray = Ray {
                o: offset_ray_origin(hit.p, hit.p_err, hit.n, bs.wi),
                d: bs.wi,
            };

            // Step 7 - Russian roulette, as on camera paths but from bounce rr_start on
            // (LIGHT_SUBPATH_RR_START_BOUNCE for BDPT and VCM, RR_START_BOUNCE otherwise):
            // continue with probability q = min(max(scattered), 0.95) and divide by q.
            if bounce >= rr_start {
                let q = scattered.max_element().min(RR_MAX_SURVIVAL);
                if u[3] >= q {
                    break;
                }
                scattered /= q;
                throughput /= q;
            }
            bounce += 1;
        }
        rays
    }
}
