//! The camera pass of bidirectional path tracing (Veach's thesis, ch. 10): one camera subpath per
//! pixel (n_c of them where the pixel sees a mirror or glass, `subpath::camera_subpaths`), and at
//! each of its vertices every strategy that ends there: the emitter it hits (s = 0), next-event
//! estimation (s = 1) and a connection to each stored vertex of the light subpath traced for this
//! pixel in the light pass (s ≥ 2). The strategies with t = 1 are the light pass's splats
//! (`light_path.rs`). Each contribution carries its MIS weight over every strategy that can make
//! its path (`crate::transport::subpath`), so the sum over strategies is unbiased. Where the scene
//! has planar mirrors, BDPT's next-event estimation also aims at the light's image in each (step
//! 4b), and the paths it makes are its alone, a partition of the weights
//! (`crate::transport::planar_mirror`). The visibility rays of next-event estimation and of the
//! connections are rouletted by their contribution (`subpath::shadow_survival`).
//!
//! The same pass, with photons, is the camera pass of the merging methods. VCM (Georgiev et al.
//! 2012) adds at every diffuse vertex the strategy that merges: every light vertex of the iteration
//! (of any pixel's light subpath) within the radius r, found in the hash grid
//! (`crate::accel::hash_grid`), weighed by MIS with all the others (`subpath::weight_merge`, its
//! two sides added here: `merge_camera_share` once per query, `merge_light_share` per photon, which
//! both backends keep in a `PhotonRecord` per grid entry; the same arithmetic in the same order). With the radius 0 it
//! is BDPT, bit for bit. SPPM is the special case without connections (Georgiev's PPM, as Knaus and
//! Zwicker's probabilistic PPM): the camera subpath follows mirrors and glass to its first diffuse
//! vertex, merges there with weight 1 and stops; it keeps the emission it meets on the way, the
//! only paths merging cannot make.
//!
//! `shaders/bdpt.wgsl` is this function again, with the same names, steps and step comments.
//!
//! Light subpaths are stored whole, however long (up to where the light pass ends them for
//! next-event estimation through a planar mirror): on the CPU as a slice per subpath, on the GPU
//! in a pool that a wave of subpaths may overflow (the iteration is then traced again in smaller
//! waves). No strategy is ever missing from the weights for want of storage. The CPU holds a
//! merging iteration's photons at once; the GPU, when they outgrow its pool, merges wave by
//! wave and takes the other strategies in the pixel's own wave (`own` in `shaders/bdpt.wgsl`),
//! which sums to the same estimate.

use crate::accel::bvh::intersect_closest;
use crate::accel::hash_grid::HashGrid;
use crate::accel::packet::occluded_all;
use crate::cpu::light_path::max_path_edges;
use crate::cpu::path::{RR_MAX_SURVIVAL, RR_START_BOUNCE};
use crate::layout::{FlatScene, KIND_EMITTER};
use crate::math::geometry::{offset_ray_origin, Ray};
use crate::math::sampling::{
    dim_bsdf, dim_connection, dim_light, dim_merge, dim_mirror, Sampler, DIM_CAMERA,
};
use crate::transport::bsdf::is_diffuse;
use crate::transport::bsdf::{eval_diffuse, sample_bsdf, Transport};
use crate::transport::camera::Camera;
use crate::transport::faults::Faults;
use crate::transport::light::{area_to_solid_angle, emitter_pdf_area, sample_emitter};
use crate::transport::merging::{footprint_share, merge_share};
use crate::transport::planar_mirror::{
    image, planar_mirror_of, starts_by_a_mirror, takes_mirror_light,
};
use crate::transport::subpath::{
    density_vanishes, merge_camera_share, merge_survival, shadow_survival, weight_connection,
    weight_emission, weight_next_event, LightVertex, MergeMis, PhotonRecord, SubpathMis,
    MERGE_RR_THRESHOLD,
};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Everything one camera pass shares.
pub struct CameraPass<'a> {
    pub scene: &'a FlatScene,
    pub camera: &'a Camera,
    /// N: light subpaths per iteration (one per pixel).
    pub n_light_paths: u32,
    pub faults: Faults,
    /// τ of the Russian roulette on visibility rays (`shadow_probe::shadow_threshold`).
    pub shadow_threshold: f32,
    /// Whether to take BDPT's strategies: emission weighed by MIS, next-event estimation and
    /// the connections (BDPT, VCM; not SPPM).
    pub connects: bool,
    /// Merging's constants in the MIS weights (`MergeMis::NONE` for BDPT).
    pub merge: MergeMis,
    /// The iteration's photons, for the merging methods.
    pub photons: Option<Photons<'a>>,
    /// The iteration's largest merge radius.
    pub radius: f32,
    /// The view's reach (`MergeRadius::reach`; 0: every vertex merges within `radius`).
    pub reach: f32,
    /// Whether merges at a vertex use its local radius (`merging::local_radius`).
    pub local_radius: bool,
}

/// What merging needs: the iteration's photons as records in the hash grid's entry order, the
/// grid, and the kernel's normalisation 1 / (π r² N).
#[derive(Clone, Copy)]
pub struct Photons<'a> {
    /// `records[j]` is the photon of `grid.entries[j]`.
    pub records: &'a [PhotonRecord],
    pub grid: &'a HashGrid,
    pub normalization: f32,
}

impl CameraPass<'_> {
    /// Adds `value` times whether surface points `a` and `b` (error bounds, unit normals) see
    /// each other, after Russian roulette on the ray by `value`, the contribution it would
    /// bring (drawing `u`): the factor is 1 / q where the ray is traced and found clear, else
    /// 0. The ray waits in `terms` to be traced with the others of the tile
    /// ([`CameraTerms::sum_into`]).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn visibility(
        &self,
        terms: &mut CameraTerms,
        a: (Vec3, Vec3, Vec3),
        b: (Vec3, Vec3, Vec3),
        value: Vec3,
        u: f32,
        rays: &mut u64,
    ) {
        let q = shadow_survival(value, self.shadow_threshold);
        if u >= q {
            terms.add(value, 0.0);
            return;
        }
        self.visibility_after_roulette(terms, a, b, value, 1.0 / q, rays);
    }

    /// Adds `value` times `factor` (1 / q of a roulette already passed) where surface points
    /// `a` and `b` see each other, else 0; the ray waits in `terms`.
    #[inline]
    fn visibility_after_roulette(
        &self,
        terms: &mut CameraTerms,
        a: (Vec3, Vec3, Vec3),
        b: (Vec3, Vec3, Vec3),
        value: Vec3,
        factor: f32,
        rays: &mut u64,
    ) {
        let to_b = b.0 - a.0;
        let origin = offset_ray_origin(a.0, a.1, a.2, to_b);
        let end = offset_ray_origin(b.0, b.1, b.2, -to_b);
        *rays += 1;
        terms.add_if_clear(
            value,
            factor,
            Ray {
                o: origin,
                d: end - origin,
            },
        );
    }

    /// The radiance that one camera subpath of pixel (x, y) gathers by the strategies with
    /// t ≥ 2, connecting to `light_path`, the light subpath of the same pixel and iteration;
    /// the pixel traces `camera_subpaths` (n_c) of them. Its terms go to `terms`, in order,
    /// as one subpath ([`CameraTerms::end_subpath`]); their sum is the radiance. `rays` counts
    /// the rays traced, the pending visibility rays included.
    #[allow(clippy::too_many_arguments)]
    pub fn trace_camera_path(
        &self,
        x: u32,
        y: u32,
        camera_subpaths: u32,
        sampler: &Sampler,
        light_path: &[LightVertex],
        terms: &mut CameraTerms,
        rays: &mut u64,
    ) {
        let (scene, camera, faults) = (self.scene, self.camera, self.faults);
        let n_paths = self.n_light_paths as f32;
        let max_edges = max_path_edges(&faults);
        // Step 1 - camera ray: a uniform point in the pixel (box filter) through the pinhole;
        // its direction's density is the importance W, n_c times over.
        let u_camera = sampler.draw4(DIM_CAMERA);
        let mut ray = camera.ray(x, y, u_camera[0], u_camera[1]);
        let cos_camera = ray.d.dot(Vec3::from(camera.forward));
        let mut mis = SubpathMis::camera(
            n_paths,
            camera_subpaths as f32 * camera.importance(cos_camera),
        );

        let mut throughput = Vec3::ONE;
        // Product of etap² over refractions, for Russian roulette (as in path.rs).
        let mut eta_scale = 1.0f32;
        let mut bounce = 0u32;
        // Next-event estimation through planar mirrors (BDPT): whether the vertex before
        // this one was diffuse, and whether this one was reached from a diffuse vertex by way
        // of a planar mirror (`planar_mirror`: such emission is that strategy's alone).
        let through_mirrors = takes_mirror_light(self.connects, self.photons.is_some(), scene);
        let mut previous_diffuse = false;
        let mut by_a_mirror = false;
        // The distance from the eye along the subpath, which sets a vertex's merge radius
        // (`merging::footprint_share`).
        let mut travelled = 0.0f32;

        loop {
            // Step 2 - closest hit; the quantities turn the direction's density into an area
            // density at the hit.
            *rays += 1;
            let Some(hit) = intersect_closest(scene, &ray, f32::MAX) else {
                break;
            };
            let material = scene.materials[hit.material as usize];
            let wo = -ray.d;
            travelled += hit.t;
            let cos_o = hit.n.dot(wo);
            if density_vanishes(cos_o) && !faults.continue_at_vanishing_density {
                // A grazing hit that no f32 density can describe ends the subpath.
                break;
            }
            mis.at_hit(hit.t * hit.t, cos_o.abs());
            // Edges of the camera subpath up to this vertex.
            let depth = bounce + 1;

            // Step 3 - emission (s = 0): an emitter seen from its front, weighted against the
            // light point taken by next-event estimation or by a light subpath (SPPM meets it
            // only through mirrors and glass, where nothing else can: weight 1). Seen from a
            // diffuse vertex in a planar mirror, it is next-event estimation's (step 4b).
            if material.kind == KIND_EMITTER && cos_o > 0.0 && depth <= max_edges && !by_a_mirror {
                let pdf_area = emitter_pdf_area(scene, hit.prim);
                let w = if self.connects {
                    weight_emission(&mis, pdf_area, cos_o * FRAC_1_PI)
                } else {
                    1.0
                };
                terms.add(throughput * Vec3::from(material.emission) * w, 1.0);
            }

            let u_light = sampler.draw4(dim_light(bounce));
            let u_bsdf = sampler.draw4(dim_bsdf(bounce));
            let diffuse = is_diffuse(&material);
            if material.kind == KIND_EMITTER && !diffuse {
                // A black emitter reflects nothing: the path ends here.
                break;
            }
            if diffuse {
                let n_facing = if cos_o < 0.0 { -hit.n } else { hit.n };
                let albedo = Vec3::from(material.color);
                let pdf_rev = cos_o.abs() * FRAC_1_PI;
                let here = (hit.p, hit.p_err, hit.n);
                // Merging's query (step 6) begins now and its entries are prefetched after
                // step 4, so that its memory reads overlap with steps 4 and 5
                // (`HashGrid::begin_query`; the CPU alone: a GPU hides the latency with other
                // invocations).
                // The merge radius here as a share of the iteration's largest (`merge_share`:
                // by the distance from the eye, and in vcm within the vertex's clearance), and
                // merging's MIS constants for it.
                let footprint = footprint_share(travelled, self.reach);
                let share = merge_share(
                    scene,
                    hit.p,
                    hit.prim,
                    self.radius,
                    footprint,
                    self.local_radius,
                );
                let merge = self.merge.within(share);
                // Russian roulette on the query (VCM): run with probability q, divided by q.
                let merging = self.photons.as_ref().and_then(|photons| {
                    let q = if self.connects {
                        merge_survival(
                            &mis,
                            &merge,
                            pdf_rev,
                            (throughput * albedo).max_element(),
                            MERGE_RR_THRESHOLD,
                        )
                    } else {
                        1.0
                    };
                    (q >= 1.0 || sampler.draw4(dim_merge(bounce))[0] < q)
                        .then(|| (photons, photons.grid.begin_query(hit.p, share), q))
                });

                // Step 4 - next-event estimation (s = 1): an emitter point chosen by power,
                // uniformly on its area, one shadow ray; weighted against BSDF sampling (s = 0)
                // and against the light subpath that would start there (s = 2).
                let ls = sample_emitter(scene, u_light[0], u_light[1], u_light[2]);
                let to_light = ls.p - hit.p;
                let dist2 = to_light.length_squared();
                let wi = to_light / dist2.sqrt();
                let cos_l = -ls.n.dot(wi);
                let bsdf = eval_diffuse(albedo, n_facing, wo, wi);
                let connects = self.connects && depth < max_edges;
                if connects && bsdf.pdf > 0.0 && cos_l > 0.0 && dist2 > 0.0 {
                    let pdf_light = area_to_solid_angle(ls.pdf_area, dist2, cos_l);
                    let pdf_emit = cos_l * FRAC_1_PI * bsdf.cos_i / dist2;
                    let w = weight_next_event(&mis, &merge, bsdf.pdf, pdf_light, pdf_emit, pdf_rev);
                    let value = throughput * bsdf.f * ls.le * (bsdf.cos_i * w / pdf_light);
                    let light = (ls.p, ls.p_err, ls.n);
                    self.visibility(terms, here, light, value, u_bsdf[3], rays);
                }

                // Step 4b - next-event estimation through each planar mirror: the same emitter
                // point, reflected in the mirror's plane, is a light of the same area density;
                // the path x → m → y has the image's geometry term and the mirror's
                // reflectance, and weight 1 (`planar_mirror`). A closest-hit ray finds m on the
                // mirror with x m clear, a shadow ray m y.
                if through_mirrors && depth + 1 < max_edges {
                    let u_mirror = sampler.draw4(dim_mirror(bounce));
                    for (i, mirror) in scene.planar_mirrors.iter().enumerate() {
                        let Some((y_image, n_image)) = image(mirror, hit.p, ls.p, ls.n) else {
                            continue;
                        };
                        let to_image = y_image - hit.p;
                        let dist2 = to_image.length_squared();
                        let wi = to_image / dist2.sqrt();
                        let cos_l = -n_image.dot(wi);
                        let bsdf = eval_diffuse(albedo, n_facing, wo, wi);
                        if bsdf.pdf <= 0.0 || cos_l <= 0.0 || dist2 <= 0.0 {
                            continue;
                        }
                        // The mirror's reflectance (a specular bounce: the test-only
                        // specular_scale too).
                        let reflectance =
                            Vec3::from(scene.materials[mirror.material as usize].color)
                                * faults.specular_scale;
                        let value = throughput
                            * bsdf.f
                            * reflectance
                            * ls.le
                            * (bsdf.cos_i * cos_l / (dist2 * ls.pdf_area));
                        let q = shadow_survival(value, self.shadow_threshold);
                        if u_mirror[i] >= q {
                            continue;
                        }
                        *rays += 1;
                        let to_mirror = Ray {
                            o: offset_ray_origin(hit.p, hit.p_err, hit.n, wi),
                            d: wi,
                        };
                        let Some(mirror_hit) = intersect_closest(scene, &to_mirror, f32::MAX)
                            .filter(|h| planar_mirror_of(scene, h.prim) == Some(i))
                        else {
                            continue;
                        };
                        let light = (ls.p, ls.p_err, ls.n);
                        self.visibility_after_roulette(
                            terms,
                            (mirror_hit.p, mirror_hit.p_err, mirror_hit.n),
                            light,
                            value,
                            1.0 / q,
                            rays,
                        );
                    }
                }

                if let Some((photons, query, _)) = &merging {
                    photons.grid.prefetch_entries(query, photons.records);
                }

                // Step 5 - connections (s ≥ 2): to each vertex of this pixel's light subpath,
                // one shadow ray each; the contribution is β f_c G f_l α, weighted against
                // every other strategy on both sides.
                for (i, v) in light_path.iter().enumerate().filter(|_| self.connects) {
                    if depth + 1 + v.length > max_edges {
                        continue;
                    }
                    let lp = Vec3::from(v.p);
                    let to_light = lp - hit.p;
                    let dist2 = to_light.length_squared();
                    let dir = to_light / dist2.sqrt();
                    let camera_bsdf = eval_diffuse(albedo, n_facing, wo, dir);
                    let light_albedo = Vec3::from(scene.materials[v.material as usize].color);
                    let light_bsdf =
                        eval_diffuse(light_albedo, Vec3::from(v.n), Vec3::from(v.wo), -dir);
                    if camera_bsdf.pdf <= 0.0 || light_bsdf.pdf <= 0.0 || dist2 <= 0.0 {
                        continue;
                    }
                    let g = camera_bsdf.cos_i * light_bsdf.cos_i / dist2;
                    let light_mis = SubpathMis {
                        d_vcm: v.d_vcm,
                        d_vc: v.d_vc,
                        d_vm: v.d_vm,
                    };
                    let w = weight_connection(
                        &mis,
                        &light_mis,
                        &merge,
                        camera_bsdf.pdf * light_bsdf.cos_i / dist2,
                        camera_bsdf.pdf_rev,
                        light_bsdf.pdf * camera_bsdf.cos_i / dist2,
                        light_bsdf.pdf_rev,
                    );
                    let value = throughput
                        * camera_bsdf.f
                        * light_bsdf.f
                        * Vec3::from(v.throughput)
                        * (g * w);
                    let there = (lp, Vec3::splat(v.p_err), Vec3::from(v.n));
                    let u = sampler.draw4(dim_connection(bounce, i as u32))[i % 4];
                    self.visibility(terms, here, there, value, u, rays);
                }

                // Step 6 - merging (VCM, SPPM): every photon of the iteration within r on the
                // same side of the surface, counted with the disk kernel 1 / (π r² N) times
                // f α, weighted against every other strategy (SPPM: 1). The photon is taken
                // as arrived here: Lambert's f = ρ/π, and the densities of its direction
                // use its own normal's cosine, which stays positive across the disk. Within
                // this vertex's radius share · r: the kernel's 1 / (π r² N) and the record's
                // light-side term (∝ vc ∝ r^−2β) scale with it.
                if let Some((photons, query, q)) = &merging {
                    let mut gathered = Vec3::ZERO;
                    let camera_share = merge_camera_share(&mis, &merge, pdf_rev);
                    let area_share = share * share;
                    let vc_share = crate::transport::subpath::mis(area_share);
                    let radius = share * self.radius;
                    photons
                        .grid
                        .finish_query_slots_within(query, radius * radius, |j| {
                            let v = &photons.records[j];
                            let n_light = Vec3::from(v.n);
                            if depth + v.length > max_edges || n_light.dot(n_facing) <= 0.0 {
                                return;
                            }
                            // subpath::weight_merge, its two sides added as the shader adds them.
                            let w = if self.connects {
                                1.0 / (v.w_light / vc_share + 1.0 + camera_share)
                            } else {
                                1.0
                            };
                            gathered += Vec3::from(v.throughput) * w;
                        });
                    let q = if faults.merge_rr_undivided { 1.0 } else { *q };
                    terms.add(
                        throughput
                            * albedo
                            * gathered
                            * (FRAC_1_PI * photons.normalization / area_share / q),
                        1.0,
                    );
                }
                if !self.merge.camera_goes_on {
                    // SPPM and VCM end the camera subpath at its first diffuse vertex
                    // (`subpath`, "VCM at the first diffuse vertex").
                    break;
                }
            }

            // Step 7 - scattering: sample the BSDF for the next direction; the throughput takes
            // the sample's weight and the quantities its densities.
            let bs = sample_bsdf(&material, hit.n, wo, u_bsdf, Transport::Radiance);
            let cos_out = hit.n.dot(bs.wi).abs();
            throughput *= bs.weight;
            if bs.pdf == 0.0 {
                throughput *= faults.specular_scale;
                mis.after_specular(cos_out);
            } else {
                mis.after_diffuse(cos_out, bs.pdf, cos_o.abs() * FRAC_1_PI, &self.merge);
            }
            eta_scale *= bs.eta2;
            if throughput.max_element() <= 0.0 || depth >= max_edges {
                break;
            }
            // The light end (emitter, this vertex, the one before) that the partition gives to
            // step 4b: the predicate the light pass applies to its first two hits.
            by_a_mirror = through_mirrors
                && !faults.mirror_light_twice
                && starts_by_a_mirror(scene, hit.prim, previous_diffuse);
            previous_diffuse = diffuse;
            ray = Ray {
                o: offset_ray_origin(hit.p, hit.p_err, hit.n, bs.wi),
                d: bs.wi,
            };

            // Step 8 - Russian roulette, as in path.rs: from bounce RR_START_BOUNCE on,
            // continue with probability q = min(max(throughput) · eta_scale, 0.95) and divide
            // by q.
            if bounce >= RR_START_BOUNCE {
                let q = (throughput.max_element() * eta_scale).min(RR_MAX_SURVIVAL);
                if u_light[3] >= q {
                    break;
                }
                throughput /= q;
            }
            bounce += 1;
        }
        terms.end_subpath();
    }
}

/// The terms of a tile's camera subpaths, in the order each subpath adds them, with their
/// visibility rays: the CPU traces a tile's visibility rays together, eight at a time in SIMD
/// lanes (`packet::occluded_all`), and then sums each subpath's terms in its own order, so
/// the sum is bit for bit that of tracing each ray at once, as `shaders/bdpt.wgsl` does. A
/// term is value x factor, the factor 0 where its ray is blocked; terms without a ray (the
/// emission, the merges, a ray that roulette did not trace) keep their factor (1, or 0).
#[derive(Default)]
pub struct CameraTerms {
    /// (value, factor, index of the ray in `rays` or `NO_RAY`).
    terms: Vec<(Vec3, f32, u32)>,
    rays: Vec<Ray>,
    blocked: Vec<bool>,
    /// Where each subpath's terms end.
    ends: Vec<usize>,
}

const NO_RAY: u32 = u32::MAX;

impl CameraTerms {
    /// Visibility rays past which a tile's terms are summed before it takes the next pixel,
    /// so that a tile of long subpaths holds bounded memory (the sums are the same).
    pub const RAYS_BEFORE_SUM: usize = 4096;

    /// The visibility rays waiting to be traced.
    pub fn pending_rays(&self) -> usize {
        self.rays.len()
    }

    #[inline]
    fn add(&mut self, value: Vec3, factor: f32) {
        self.terms.push((value, factor, NO_RAY));
    }

    #[inline]
    fn add_if_clear(&mut self, value: Vec3, factor: f32, ray: Ray) {
        self.terms.push((value, factor, self.rays.len() as u32));
        self.rays.push(ray);
    }

    #[inline]
    fn end_subpath(&mut self) {
        self.ends.push(self.terms.len());
    }

    /// Traces the visibility rays, appends each subpath's radiance to `radiance` in the order
    /// the subpaths were traced, and empties itself, keeping the storage.
    pub fn sum_into(&mut self, scene: &FlatScene, radiance: &mut Vec<Vec3>) {
        self.blocked.clear();
        self.blocked.resize(self.rays.len(), false);
        occluded_all(scene, &self.rays, &mut self.blocked);
        let mut start = 0;
        for &end in &self.ends {
            let mut sum = Vec3::ZERO;
            for &(value, factor, ray) in &self.terms[start..end] {
                let clear = ray == NO_RAY || !self.blocked[ray as usize];
                sum += value * if clear { factor } else { 0.0 };
            }
            start = end;
            radiance.push(sum);
        }
        debug_assert_eq!(start, self.terms.len(), "terms after the last subpath");
        self.terms.clear();
        self.rays.clear();
        self.ends.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::sampling::{pcg4d, u32_to_unit_f32};
    use crate::transport::method::Method;
    use crate::transport::subpath::weight_merge;

    /// A number in [0, scale) for test data: number `k` of item `i`.
    fn rnd(i: u32, k: u32, scale: f32) -> f32 {
        u32_to_unit_f32(pcg4d([i, k, 17, 4])[0]) * scale
    }

    /// A merge through a photon's record weighs it exactly as `subpath::weight_merge` does on
    /// the vertex itself: the light side is the same f32 arithmetic, done once per photon; for
    /// vcm, whose camera subpaths end at their first diffuse vertex, without the photon's d_vm.
    #[test]
    fn a_merge_through_the_record_weighs_as_weight_merge() {
        for method in [Method::VcmFull, Method::Vcm] {
            records_weigh_as_weight_merge(method);
        }
    }

    fn records_weigh_as_weight_merge(method: Method) {
        let merge = MergeMis::new(0.01, 512 * 512, method);
        for i in 0..1000 {
            let n = Vec3::new(
                rnd(i, 0, 2.0) - 1.0,
                rnd(i, 1, 2.0) - 1.0,
                rnd(i, 2, 2.0) - 1.0,
            )
            .normalize();
            let wo = Vec3::new(
                rnd(i, 3, 2.0) - 1.0,
                rnd(i, 4, 2.0) - 1.0,
                rnd(i, 5, 2.0) - 1.0,
            )
            .normalize();
            let v = LightVertex {
                n: n.into(),
                wo: wo.into(),
                length: 1 + i % 7,
                throughput: [rnd(i, 6, 3.0), rnd(i, 7, 3.0), rnd(i, 8, 3.0)],
                d_vcm: rnd(i, 9, 50.0),
                d_vc: rnd(i, 10, 50.0),
                d_vm: rnd(i, 11, 50.0),
                ..LightVertex::default()
            };
            let camera = SubpathMis {
                d_vcm: rnd(i, 12, 50.0),
                d_vc: rnd(i, 13, 50.0),
                d_vm: rnd(i, 14, 50.0),
            };
            let pdf_rev = rnd(i, 15, FRAC_1_PI);
            let light = SubpathMis {
                d_vcm: v.d_vcm,
                d_vc: v.d_vc,
                d_vm: v.d_vm,
            };
            let expected = weight_merge(&camera, &light, &merge, n.dot(wo) * FRAC_1_PI, pdf_rev);
            // Eqs. 37-39 written out, apart from the functions both sides share.
            let c = n.dot(wo) * FRAC_1_PI;
            let beyond = if method == Method::VcmFull {
                v.d_vm * (c * c)
            } else {
                0.0
            };
            let written_out = 1.0
                / (v.d_vcm * merge.vc
                    + beyond
                    + 1.0
                    + (camera.d_vcm * merge.vc + camera.d_vm * (pdf_rev * pdf_rev)));
            let record = PhotonRecord::new(&v, &merge, true);
            let got = 1.0 / (record.w_light + 1.0 + merge_camera_share(&camera, &merge, pdf_rev));
            assert_eq!(got.to_bits(), expected.to_bits(), "photon {i}");
            assert_eq!(got.to_bits(), written_out.to_bits(), "photon {i}");
            assert_eq!(
                (record.n, record.length, record.throughput),
                (v.n, v.length, v.throughput)
            );
        }
    }
}
