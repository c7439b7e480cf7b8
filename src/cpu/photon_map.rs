//! Photon mapping in Jensen's two-pass form ("Global illumination using photon maps", 1996;
//! "Realistic Image Synthesis Using Photon Mapping", 2001, ch. 9), the method of both TNCG15
//! reports: the camera pass of `--method photon-map`.
//!
//! The first pass is the light pass (`light_path.rs`, mode `CausticAndGlobal`): N light subpaths
//! an iteration, each storing a photon (its flux α) at every diffuse surface it meets after its
//! first hit. The photons form two maps in one hash grid:
//! - the **caustic map**: photons that came from the light by mirrors and glass alone (paths
//!   L S+ D);
//! - the **global map**: photons that scattered diffusely at least once before (L (S|D)* D S* D).
//!
//! The light's first hits (L D, the direct light) are not stored: next-event estimation takes
//! direct light everywhere. Which map a photon is in needs no field of its own: with merging's
//! vc = 0 (no connections), the MIS quantity d_vm of a light vertex is 0 until the subpath's first
//! diffuse scattering and above 0 from then on (`SubpathMis::after_diffuse` adds 1 there and
//! nothing else adds to it), so d_vm > 0 is the global map (`PhotonRecord::w_light` holds it).
//!
//! The second pass, this one, splits the light reaching each diffuse point x the camera sees
//! (through mirrors and glass) into parts that together are all of it, each estimated where it is
//! smoothest:
//!
//!   L(x → eye) = Le + L_direct(x) + L_caustic(x) + ∫ f(x) L_o(y → x) cos θ dω,
//!
//! - Le: an emitter the camera sees, straight or through mirrors and glass;
//! - L_direct: next-event estimation, one emitter point (sharp shadows);
//! - L_caustic: the caustic map's density estimate at x, (ρ/π) Σ α_p / (π r² N) over the photons
//!   within r on the side x is seen from;
//! - the rest by **final gathering**: one cosine-sampled direction from x, followed through
//!   mirrors and glass to the first diffuse point y, where L_o(y) = L_direct(y) + L_caustic(y) +
//!   L_global(y), the last the global map's estimate. An emitter the gather ray meets adds
//!   nothing: that light is L_direct's or L_caustic's at x.
//!
//! The density estimate counts the photons within a fixed radius r (a ball, found in the hash
//! grid, `crate::accel::hash_grid`), not the k nearest: on a GPU a fixed radius is one query of at
//! most eight buckets with no per-thread heap, the same on both backends, and the grid is the one
//! SPPM and VCM build. The radius does not shrink over iterations (not progressive): every
//! iteration is an independent photon map of the same radius, so averaging iterations removes
//! noise but not the bias of blurring the light over the disk (O(r²) where it is smooth, more at
//! edges and in sharp caustics). The bias is fixed by r, whatever the number of samples; the
//! summary line and the EXR metadata say so.
//!
//! `shaders/photon_map.wgsl` is this function again, with the same names, steps and step
//! comments.

use crate::accel::bvh::{intersect_closest, occluded};
use crate::cpu::bdpt::Photons;
use crate::cpu::light_path::max_path_edges;
use crate::cpu::path::{RR_MAX_SURVIVAL, RR_START_BOUNCE};
use crate::layout::{FlatScene, KIND_EMITTER};
use crate::math::geometry::{offset_ray_origin, Ray};
use crate::math::sampling::{dim_bsdf, dim_light, Sampler, DIM_CAMERA};
use crate::transport::bsdf::{is_diffuse, sample_bsdf, Transport};
use crate::transport::camera::Camera;
use crate::transport::faults::Faults;
use crate::transport::light::{link_to_emitter, sample_emitter};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Which photons a density estimate counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhotonMap {
    /// Photons that came from the light by mirrors and glass alone (L S+ D).
    Caustic,
    /// Every stored photon: the caustic map's and those after a diffuse scattering.
    CausticAndGlobal,
}

/// Everything one camera pass of photon mapping shares.
pub struct PhotonMapPass<'a> {
    pub scene: &'a FlatScene,
    pub camera: &'a Camera,
    pub faults: Faults,
    /// The iteration's photons (both maps) and the kernel's 1 / (π r² N).
    pub photons: Photons<'a>,
    /// The radius r of the density estimates.
    pub radius: f32,
}

impl PhotonMapPass<'_> {
    /// The density estimate of `map` at diffuse point `p`, seen from the side of `n_facing`,
    /// reached by a camera subpath of `depth` edges: Σ α_p / (π r² N) over the photons within r
    /// on that side whose paths, joined to the camera subpath's, stay within the edges the
    /// `max_bounces` fault allows; times ρ/π it is the reflected radiance.
    fn density(&self, p: Vec3, n_facing: Vec3, depth: u32, map: PhotonMap) -> Vec3 {
        let photons = &self.photons;
        let max_edges = max_path_edges(&self.faults);
        let mut gathered = Vec3::ZERO;
        let query = photons.grid.begin_query(p, 1.0);
        photons
            .grid
            .finish_query_slots_within(&query, self.radius * self.radius, |j| {
                let v = &photons.records[j];
                // w_light > 0: the photon scattered diffusely before (the global map).
                let caustic = v.w_light <= 0.0;
                if (map == PhotonMap::Caustic && !caustic)
                    || depth + v.length > max_edges
                    || Vec3::from(v.n).dot(n_facing) <= 0.0
                {
                    return;
                }
                gathered += Vec3::from(v.throughput);
            });
        gathered * photons.normalization
    }

    /// The radiance that one camera sample of pixel (x, y) gathers. `rays` counts the rays
    /// traced (closest-hit and shadow).
    pub fn trace_camera_path(&self, x: u32, y: u32, sampler: &Sampler, rays: &mut u64) -> Vec3 {
        let (scene, faults) = (self.scene, self.faults);
        let max_edges = max_path_edges(&faults);
        // Step 1 - camera ray: a uniform point in the pixel (box filter) through the pinhole.
        let u_camera = sampler.draw4(DIM_CAMERA);
        let mut ray = self.camera.ray(x, y, u_camera[0], u_camera[1]);

        let mut radiance = Vec3::ZERO;
        let mut throughput = Vec3::ONE;
        // Product of etap² over refractions, for Russian roulette (as in `path.rs`).
        let mut eta_scale = 1.0f32;
        // Whether the subpath has passed x, its first diffuse point: it is then the gather ray.
        let mut gathering = false;
        let mut bounce = 0u32;

        loop {
            // Step 2 - closest hit: the nearest surface along the ray over the BVH.
            *rays += 1;
            let Some(hit) = intersect_closest(scene, &ray, f32::MAX) else {
                break;
            };
            let material = scene.materials[hit.material as usize];
            let wo = -ray.d;
            let cos_o = hit.n.dot(wo);
            // Edges of the camera subpath up to this vertex.
            let depth = bounce + 1;

            // Step 3 - emission: an emitter seen from its front by the camera, straight or
            // through mirrors and glass. Met by the gather ray, its light is x's direct or
            // caustic light, taken in steps 4 and 5.
            if material.kind == KIND_EMITTER && cos_o > 0.0 && !gathering && depth <= max_edges {
                radiance += throughput * Vec3::from(material.emission);
            }
            let diffuse = is_diffuse(&material);
            if material.kind == KIND_EMITTER && !diffuse {
                // A black emitter reflects nothing: the path ends here.
                break;
            }
            let u_light = sampler.draw4(dim_light(bounce));
            let u_bsdf = sampler.draw4(dim_bsdf(bounce));
            if diffuse {
                let n_facing = if cos_o < 0.0 { -hit.n } else { hit.n };
                let f = Vec3::from(material.color) * FRAC_1_PI;

                // Step 4 - direct light: one point on the emitters (an emitter by power, a
                // uniform point on it), one shadow ray, f · Le · cos θ / p_ω.
                let ls = sample_emitter(scene, u_light[0], u_light[1], u_light[2]);
                if depth < max_edges {
                    if let Some(link) = link_to_emitter(hit.p, hit.p_err, hit.n, n_facing, &ls) {
                        *rays += 1;
                        if !occluded(scene, &link.shadow, 1.0) {
                            radiance += throughput * f * link.le * (link.cos_s / link.light_pdf);
                        }
                    }
                }

                // Step 5 - the photon maps: at x the caustic map; at y, the gather ray's end, the
                // caustic and the global map (all the light that has scattered since it left
                // the light, direct light apart). Then the subpath ends at y.
                let map = if gathering {
                    PhotonMap::CausticAndGlobal
                } else {
                    PhotonMap::Caustic
                };
                radiance += throughput * f * self.density(hit.p, n_facing, depth, map);
                if gathering {
                    break;
                }
                gathering = true;
            }

            // Step 6 - scattering: at x the gather ray, a cosine-distributed direction (weight ρ);
            // at mirrors and glass the specular bounce.
            let bs = sample_bsdf(&material, hit.n, wo, u_bsdf, Transport::Radiance);
            throughput *= bs.weight;
            if bs.pdf == 0.0 {
                throughput *= faults.specular_scale;
            }
            eta_scale *= bs.eta2;
            if throughput.max_element() <= 0.0 || depth >= max_edges {
                break;
            }
            ray = Ray {
                o: offset_ray_origin(hit.p, hit.p_err, hit.n, bs.wi),
                d: bs.wi,
            };

            // Step 7 - Russian roulette, as in `path.rs`: from bounce RR_START_BOUNCE on,
            // continue with probability q = min(max(throughput) · eta_scale, 0.95) and divide
            // by q (it ends the long chains of mirrors and glass).
            if bounce >= RR_START_BOUNCE {
                let q = (throughput.max_element() * eta_scale).min(RR_MAX_SURVIVAL);
                if u_light[3] >= q {
                    break;
                }
                throughput /= q;
            }
            bounce += 1;
        }
        radiance
    }
}
