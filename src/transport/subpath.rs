//! What the bidirectional methods (light tracing, BDPT) share: the stored light vertex, and
//! multiple importance sampling over connection strategies by recursive quantities, so that no
//! whole path is ever stored.
//!
//! A full path x0 (the pinhole) … xk (on an emitter) can be sampled by several strategies: s of
//! its vertices from a light subpath and t = k + 1 − s from a camera subpath, joined by one
//! connection. BDPT takes every strategy that can make the path and weighs each with the
//! power heuristic (β = 2, Veach's thesis eq. 9.13; but for the paths whose light end is a
//! light point, a planar mirror and a diffuse vertex, which next-event estimation through the
//! mirror takes alone: `crate::transport::planar_mirror`), w_s = (n_s p_s)² / Σ_i (n_i p_i)², where
//! p_i is the area-measure density of the whole path under strategy i and n_i the number of
//! samples strategy i takes per pixel and iteration: N (the number of light subpaths) for t = 1,
//! whose light subpaths may land in any pixel, and for the others n_c(j), the camera subpaths
//! that pixel j traces per iteration (see [`camera_subpaths`]). n_c enters every formula as a
//! factor on the camera's density W, which is what tracing n_c camera subpaths amounts to.
//! Strategies that would connect at a specular vertex cannot make the path and leave the sum.
//!
//! The sum is kept as Georgiev et al.'s recursive quantities ("Light transport simulation with
//! vertex connection and merging", SIGGRAPH Asia 2012, and its technical report, the form of
//! SmallVCM): at every subpath vertex two numbers, d_vcm and d_vc, from which the partial sum over
//! all strategies on that subpath's side follows with the one or two densities that only the
//! connection knows, and a third, d_vm, for the strategies that merge (vertex merging,
//! `crate::transport::merging`). Merging enters through two constants of the iteration
//! ([`MergeMis`]): η = π r² N, the ratio of a merge's density to a connection's (the N light
//! subpaths of an iteration each offer a photon within the disk of area π r², Georgiev et al., eq.
//! 20 of the report), as vm = η^β and vc = η^−β; without merging both are 0 and the quantities are
//! BDPT's exactly (every vm and vc term adds or multiplies a 0).
//!
//! VCM at the first diffuse vertex (`vcm`, the default; `vcm-full` is Georgiev et al.'s as
//! published): the camera subpath follows mirrors and glass to its first diffuse vertex, as
//! SPPM's does, and ends there, after next-event estimation, a connection to each vertex of its
//! light subpath and a merge. A path x0 … xk whose first diffuse vertex seen from the camera is
//! xd can then be made by the connection at xd (t = d + 1, next-event estimation where s = 1),
//! the merge at xd, light tracing where d = 1, and emission where the camera meets the emitter
//! before any diffuse vertex; every strategy whose camera subpath would go on past xd is gone.
//! Those are the terms on the light side of a connection (and of next-event estimation), the
//! light vertex's d_vc in light tracing and its d_vm in a merge, all of which a camera subpath
//! that went on would have made; the weights leave them out when `MergeMis::camera_goes_on` is
//! false, and the rest are a partition of unity over exactly the strategies taken
//! (`tests/mis_weights.rs`). The camera side needs no change: before xd its vertices are
//! specular, where nothing connects or merges. Every path with a diffuse vertex keeps the merge
//! (the photon arrives at xd whatever lies beyond), so the method stays consistent; with the
//! radius 0 it is BDPT, whose camera subpaths go on. Why: at the default radius the merge at
//! the first diffuse vertex carries most of the weight of the paths through it, and a camera
//! subpath that goes on pays for connections and merges further on, whose share is small and
//! noisy (a one-sample final gather); ending there doubles the iterations in the same time
//! (docs/journal/2026-11-27_first_diffuse.md).
//!
//! A radius of the vertex (`vcm`): since vcm's camera subpaths end at their first diffuse vertex,
//! a path has exactly one merging strategy, the merge at that vertex xd, and η enters no
//! weight but through it: in next-event estimation and the connections at xd (the merge at the
//! camera vertex, `merge.vm`), in the merge itself (vc), and in light tracing where d = 1 (the
//! light vertex is xd). The light subpath's d_vc and d_vm, which carry η for merges at other
//! vertices, are left out of every weight. So the radius may be any function of xd, and every
//! strategy that makes a path weighs its merge with the same r(xd): vcm merges within a share
//! of the iteration's largest radius r_i set by xd's distance from the eye along the camera
//! subpath (`merging::footprint_share`; light tracing, where d = 1, takes |xd − eye|) and
//! limited by xd's clearance (`merging::local_radius`) ([`MergeMis::within`]), and the weights
//! stay a partition of unity. SPPM, whose weights are 1, takes the share by distance too.
//! vcm-full, whose paths may merge at any of their diffuse vertices, keeps one radius.
//!
//! Why the power heuristic: it is the path tracer's already (so its NEE and its BSDF sampling of
//! emitters weigh alike in both methods), and where one strategy is much better than the others,
//! which is the rule here (light tracing for caustics seen directly, camera paths for the room
//! seen in a mirror), it gives the poor ones less weight than the balance heuristic does
//! (Veach, section 9.2.3).
//!
//! The densities are those of the sampling decisions alone, without Russian roulette's survival
//! probabilities: hexray's roulette depends on the throughput so far, which is not a function of
//! the path for the reverse direction. Any weights that sum to 1 over the strategies that can
//! make a path keep the combination unbiased (Veach, eq. 9.4), and these do, so roulette stays
//! out of them (pbrt-v4's BDPT leaves it out as well).

use crate::accel::bvh::intersect_closest;
use crate::layout::{FlatScene, KIND_GLASS, KIND_MIRROR};
use crate::transport::camera::Camera;
use crate::transport::method::Method;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Camera subpaths per iteration in a pixel whose centre ray first meets a mirror or glass, for
/// BDPT (and VCM without merging, which is BDPT) and for SPPM (not measured for SPPM, whose camera
/// subpaths are cheap: they end at their first diffuse vertex). There the camera subpath is all
/// BDPT has: light tracing cannot reach the pixel, and what is seen in the mirror (a wall lit
/// through the mirror: camera - mirror - diffuse - mirror - light) is found by the camera subpath
/// alone, as in path tracing. With one camera subpath per iteration those pixels would get a third
/// of path tracing's samples at equal time (an iteration costs about three path-traced samples), so
/// they take several. With 5, BDPT's relMSE is 0.46 of 1's on tncg15_room and 0.50 on glass_room
/// (256x256, 30 s on 2 cores, seed 9, set by editing this constant); 8 is within the runs' noise of
/// 5, and 5 leaves more iterations (light subpaths) to the rest of the image.
pub const SPECULAR_CAMERA_SUBPATHS: u32 = 5;

/// Camera subpaths per iteration in such a pixel for VCM with merging
/// ([`specular_camera_subpaths`]). Merging gives the camera subpath that goes on through the
/// mirror what BDPT lacks there: its first diffuse vertex behind the mirror merges the light
/// that arrived by way of the mirror or glass, so a few camera subpaths do what five do
/// without merging, and each one saved leaves time to more iterations for the whole image
/// (a camera subpath with its connections and merges is most of an iteration's cost). With 2,
/// vcm's relMSE is 0.90 of 5's on tncg15_room and 0.95 on glass_room (256x256, 30 s on 2 cores,
/// seeds 11 – 13, set by editing the constant); 3 is within the runs' noise of 2 and costs more.
pub const SPECULAR_CAMERA_SUBPATHS_MERGING: u32 = 2;

/// n_c where a pixel's centre ray first meets a mirror or glass, for `method` with the initial
/// merge radius `radius` (looked at only for VCM): VCM that merges takes
/// [`SPECULAR_CAMERA_SUBPATHS_MERGING`], every other method [`SPECULAR_CAMERA_SUBPATHS`], so
/// VCM with the radius 0 is BDPT in this too.
pub fn specular_camera_subpaths(method: Method, radius: f32) -> u32 {
    if matches!(method, Method::Vcm | Method::VcmFull) && radius > 0.0 {
        SPECULAR_CAMERA_SUBPATHS_MERGING
    } else {
        SPECULAR_CAMERA_SUBPATHS
    }
}

/// Whether the ray through the centre of pixel j first meets a mirror or glass, for every
/// pixel j, row by row: the pixels that trace several camera subpaths per iteration.
pub fn specular_pixels(scene: &FlatScene, camera: &Camera) -> Vec<bool> {
    let mut out = Vec::with_capacity(camera.width as usize * camera.height as usize);
    for y in 0..camera.height {
        for x in 0..camera.width {
            out.push(
                intersect_closest(scene, &camera.ray(x, y, 0.5, 0.5), f32::MAX).is_some_and(
                    |hit| {
                        let kind = scene.materials[hit.material as usize].kind;
                        kind == KIND_MIRROR || kind == KIND_GLASS
                    },
                ),
            );
        }
    }
    out
}

/// n_c(j) for every pixel j, row by row: `count` (see [`specular_camera_subpaths`]) in the
/// `specular` pixels ([`specular_pixels`]), 1 elsewhere. A property of the pixel, fixed before
/// rendering and shared by both backends, so the MIS weights stay functions of the path (the
/// pixel a path passes is part of it).
pub fn camera_subpaths(specular: &[bool], count: u32) -> Vec<u32> {
    specular
        .iter()
        .map(|&s| if s { count } else { 1 })
        .collect()
}

/// The shadow-ray threshold as a share of the image's mean radiance (see [`shadow_survival`]):
/// 0.1. Measured as [`SPECULAR_CAMERA_SUBPATHS`] was, with 5 camera subpaths: BDPT's relMSE is
/// 2.7e-3 on tncg15_room and 1.8e-3 on glass_room, against 3.5e-3 and 2.2e-3 without the
/// roulette; 0.05 does about as well, 0.2 worse.
pub const SHADOW_RR_FRACTION: f32 = 0.1;

/// Russian roulette on the visibility rays of BDPT's connections (next-event estimation, the
/// connections to light vertices, the splats to the camera): a connection whose unoccluded,
/// MIS-weighted contribution c (its largest channel) is below the threshold τ traces its ray with
/// probability c / τ and is divided by it, which keeps it unbiased (E[V c / q · 1{u < q}] = V c)
/// and adds at most τ c of variance. Most connections of a room carry little (on tncg15_room three
/// quarters carry under 1 % of a pixel's value, together 27 % of the light), and without the
/// roulette their rays are half of an iteration's rays. Returns the probability of tracing the ray
/// (1 above the threshold, and where τ is 0).
#[inline]
pub fn shadow_survival(contribution: Vec3, threshold: f32) -> f32 {
    let c = contribution.max_element();
    if c >= threshold || threshold <= 0.0 {
        1.0
    } else {
        c / threshold
    }
}

/// The exponent of the power heuristic, applied to each density ratio.
#[inline]
pub fn mis(x: f32) -> f32 {
    x * x
}

/// Whether a hit's area density p_ω |cos θ| / dist² vanishes in f32, so that the subpath must
/// end there: mis(cos) below the smallest normal f32, |cos θ| < 1.1e-19 (exactly 0 where a ray
/// is tangent to a sphere). [`SubpathMis::at_hit`] divides by mis(cos): at a first hit that
/// is 0 / 0, later inf, and the next specular bounce, whose outgoing cosine is as small,
/// multiplies inf by 0, so every weight after it would be NaN. Such hits are met with
/// probability of the order of 1e-19 by any sampled direction, and exactly never where the
/// cosine is 0, so ending the subpath there changes no estimate that an f32 can resolve.
/// Written so that a NaN cosine ends the subpath too. `tests/stability_tangent.rs` renders a
/// camera whose every ray is tangent to a mirror sphere.
#[inline]
pub fn density_vanishes(cos: f32) -> bool {
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    !(mis(cos) >= f32::MIN_POSITIVE)
}

/// A vertex of a light subpath, stored for the camera subpaths to connect to (BDPT): only
/// vertices on non-specular surfaces, which are the only ones a connection can use. Five vec4s,
/// the same layout in `shaders/subpath.wgsl` (`LightVertex`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct LightVertex {
    pub p: [f32; 3],
    /// The largest coordinate of the point's error bound, for spawning the connection ray.
    pub p_err: f32,
    /// Unit geometric normal, turned to the side the light arrived from.
    pub n: [f32; 3],
    pub material: u32,
    /// Unit direction back toward the previous vertex of the light subpath.
    pub wo: [f32; 3],
    /// Edges from the light point: 1 for the first surface a light subpath hits.
    pub length: u32,
    /// α: the emitted radiance over the density of the light point, times f · |cos| / pdf of
    /// every scattering since, so that α · f · G · W / N is a splat's value.
    pub throughput: [f32; 3],
    /// The next vertex of the same light subpath in the GPU's vertex pool, or [`NO_VERTEX`]
    /// (unused on the CPU, where a subpath's vertices are contiguous).
    pub next: u32,
    pub d_vcm: f32,
    pub d_vc: f32,
    pub d_vm: f32,
    /// The light subpath's index (its pixel): with `length`, the vertex's place in the CPU's
    /// order, which the GPU's hash grid sorts its buckets by.
    pub path: u32,
}

/// The end of a light subpath's list of vertices (`LightVertex::next`).
pub const NO_VERTEX: u32 = u32::MAX;

/// What a merge reads of a light vertex (step 6 of the camera pass), in the hash grid's entry
/// order: 32 bytes, two to a cache line, beside the entries a query has just read. Both backends
/// build it once per photon and iteration (the CPU in `Iteration::build_grid`, the GPU in
/// `grid_records`, `shaders/hash_grid.wgsl`, the same layout as `PhotonRecord` in
/// `shaders/subpath.wgsl`). A query that read the 80-byte [`LightVertex`] at the index its entry
/// names would wait on a cache miss per photon: on the CPU at 512x512 (four times the photons a
/// query finds at 256x256) that load held a third of the camera pass's time
/// (docs/journal/2026-11-25_merge_queries.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C, align(32))]
pub struct PhotonRecord {
    /// The vertex's normal, turned to the side the light arrived from.
    pub n: [f32; 3],
    /// Edges from the light point (`LightVertex::length`).
    pub length: u32,
    /// α (`LightVertex::throughput`).
    pub throughput: [f32; 3],
    /// The light side's part of the merge weight's denominator
    /// ([`merge_light_share`], with the photon's cos θ / π toward its previous vertex).
    /// Without connections (SPPM, photon-map), whose weights are 1, the vertex's d_vm instead:
    /// above 0 exactly where its subpath scattered diffusely before it, which puts the photon in
    /// photon-map's global map (`cpu/photon_map.rs`; SPPM reads nothing of it).
    pub w_light: f32,
}

const _: () = assert!(std::mem::size_of::<PhotonRecord>() == 32);

impl PhotonRecord {
    /// The record of vertex `v` in an iteration with merging constants `merge`; `connects`
    /// says whether merges are weighed against other strategies (VCM) or not (SPPM).
    #[inline]
    pub fn new(v: &LightVertex, merge: &MergeMis, connects: bool) -> PhotonRecord {
        let w_light = if connects {
            let light_mis = SubpathMis {
                d_vcm: v.d_vcm,
                d_vc: v.d_vc,
                d_vm: v.d_vm,
            };
            let cos_light = Vec3::from(v.n).dot(Vec3::from(v.wo));
            merge_light_share(&light_mis, merge, cos_light * std::f32::consts::FRAC_1_PI)
        } else {
            v.d_vm
        };
        PhotonRecord {
            n: v.n,
            length: v.length,
            throughput: v.throughput,
            w_light,
        }
    }
}

/// The constants that merging adds to the MIS weights of an iteration: `vm` = η^β weighs the
/// merging strategies against a connection, `vc` = η^−β a connection against merging, with
/// η = π r² N (see the module comment). Both 0 without merging (BDPT).
///
/// `camera_goes_on` says whether the camera subpaths go on past their first diffuse vertex
/// (BDPT, `vcm-full`). Where they end there (`vcm`; SPPM, whose weights are 1), every strategy
/// whose camera subpath would have a diffuse vertex before its last one does not exist, and
/// the weights leave it out (see "VCM at the first diffuse vertex" in the module comment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergeMis {
    pub vm: f32,
    pub vc: f32,
    pub camera_goes_on: bool,
}

impl MergeMis {
    /// No merging: BDPT's weights.
    pub const NONE: MergeMis = MergeMis {
        vm: 0.0,
        vc: 0.0,
        camera_goes_on: true,
    };

    /// The constants for a merge within `share` times the iteration's radius: η scales as the
    /// disk's area, so vm by share^2β and vc by share^−2β (exactly these constants at 1).
    #[inline]
    pub fn within(&self, share: f32) -> MergeMis {
        let s = mis(share * share);
        MergeMis {
            vm: self.vm * s,
            vc: self.vc / s,
            camera_goes_on: self.camera_goes_on,
        }
    }

    /// The constants of an iteration of `method` that merges within `radius` among
    /// `n_light_paths` light subpaths: with connections (VCM) or without (SPPM, whose merges are
    /// its only strategy and whose weights are 1). A radius of 0 is BDPT's ([`MergeMis::NONE`]).
    pub fn new(radius: f32, n_light_paths: u32, method: Method) -> MergeMis {
        if radius <= 0.0 {
            return MergeMis::NONE;
        }
        let eta = std::f32::consts::PI * radius * radius * n_light_paths as f32;
        MergeMis {
            vm: mis(eta),
            vc: if method.connects() {
                mis(1.0 / eta)
            } else {
                0.0
            },
            camera_goes_on: method == Method::VcmFull,
        }
    }
}

/// Georgiev's recursive MIS quantities of one subpath vertex (see the module comment). For a
/// vertex x_j of either subpath, with p→(x_j) the area density with which its own subpath
/// sampled it:
/// - d_vcm = 1 / p→(x_j)^β, times N^β on the camera subpath's first vertex (the term of the
///   strategy that samples x_j from the other side next: light tracing for that vertex);
/// - d_vc carries, in the same units, the terms of every strategy that samples more of this
///   subpath's vertices from the other side, built by multiplying density ratios along it;
/// - d_vm the same for the strategies that merge at one of this subpath's earlier vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SubpathMis {
    pub d_vcm: f32,
    pub d_vc: f32,
    pub d_vm: f32,
}

impl SubpathMis {
    /// At the camera, before the first hit: the camera picked its direction with solid-angle
    /// density `pdf_camera` (the importance W), and N light subpaths compete for the pixel
    /// through t = 1. Nothing lies before the camera, so d_vc = 0.
    #[inline]
    pub fn camera(n_light_paths: f32, pdf_camera: f32) -> SubpathMis {
        SubpathMis {
            d_vcm: mis(n_light_paths / pdf_camera),
            d_vc: 0.0,
            d_vm: 0.0,
        }
    }

    /// At the light point, before the first hit: the point was picked with area density
    /// `pdf_area` and the direction with `pdf_dir` (emission density pdf_area · pdf_dir); `cos`
    /// is the emitter's cosine toward the direction. d_vcm holds the ratio of next-event
    /// estimation's density of the light point to the emission density (the strategy that
    /// takes the light point from a camera vertex's light sample), d_vc the one for the camera
    /// subpath hitting the emitter (its cosine enters, its area density cancels).
    /// d_vm: merging at the first hit, against the camera subpath that reaches the emitter.
    #[inline]
    pub fn light(pdf_area: f32, pdf_dir: f32, cos: f32, merge: &MergeMis) -> SubpathMis {
        let emission_pdf = pdf_area * pdf_dir;
        let d_vc = mis(cos / emission_pdf);
        SubpathMis {
            d_vcm: mis(pdf_area / emission_pdf),
            d_vc,
            d_vm: d_vc * merge.vc,
        }
    }

    /// At a hit `dist2` (squared) from the previous vertex, with |cos θ| between the surface's
    /// normal and the arriving ray: the solid-angle density of the sampled direction becomes an
    /// area density, p_A = p_ω |cos θ| / dist². The caller has ended the subpath where that
    /// density vanishes ([`density_vanishes`]).
    #[inline]
    pub fn at_hit(&mut self, dist2: f32, cos: f32) {
        self.d_vcm *= mis(dist2);
        self.d_vcm /= mis(cos);
        self.d_vc /= mis(cos);
        self.d_vm /= mis(cos);
    }

    /// After sampling a direction at a non-specular vertex with solid-angle density `pdf` and
    /// cosine `cos_out` toward it; `pdf_rev` is the density of sampling the arriving direction
    /// the other way. Every strategy counted so far gains one more ratio; the one that
    /// connects at this vertex joins the sum (d_vcm before the update), and with merging the
    /// one that merges here (vm in d_vc; in d_vm the connection, vc, and the merge itself, 1).
    #[inline]
    pub fn after_diffuse(&mut self, cos_out: f32, pdf: f32, pdf_rev: f32, merge: &MergeMis) {
        let ratio = mis(cos_out / pdf);
        self.d_vc = ratio * (self.d_vc * mis(pdf_rev) + self.d_vcm + merge.vm);
        self.d_vm = ratio * (self.d_vm * mis(pdf_rev) + self.d_vcm * merge.vc + 1.0);
        self.d_vcm = mis(1.0 / pdf);
    }

    /// After a specular bounce with cosine `cos_out`: no strategy can connect at this vertex
    /// (d_vcm = 0); its forward and reverse Dirac densities are equal and cancel (for glass the
    /// Fresnel choice is the same both ways), leaving the cosine.
    #[inline]
    pub fn after_specular(&mut self, cos_out: f32) {
        self.d_vcm = 0.0;
        self.d_vc *= mis(cos_out);
        self.d_vm *= mis(cos_out);
    }
}

/// The weight of a camera subpath finding an emitter (s = 0) at a vertex with these quantities:
/// the other strategies take the emitter point by next-event estimation (area density
/// `pdf_area`) or by light subpaths as well (emission density `pdf_area · pdf_dir`, `pdf_dir`
/// the emitter's density toward the previous vertex).
#[inline]
pub fn weight_emission(camera: &SubpathMis, pdf_area: f32, pdf_dir: f32) -> f32 {
    let others = mis(pdf_area) * camera.d_vcm + mis(pdf_area * pdf_dir) * camera.d_vc;
    1.0 / (1.0 + others)
}

/// The weight of next-event estimation (s = 1) from a camera vertex: `pdf_bsdf` is the
/// vertex's solid-angle density toward the light point and `pdf_light` next-event estimation's
/// (area density converted to solid angle), `pdf_emit` the light subpath's area density of
/// the camera vertex (emission toward it), `pdf_rev` the vertex's density toward where its
/// camera subpath came from. With merging, the light subpath that would start at the light
/// point may also merge at the camera vertex (`merge.vm`).
#[inline]
pub fn weight_next_event(
    camera: &SubpathMis,
    merge: &MergeMis,
    pdf_bsdf: f32,
    pdf_light: f32,
    pdf_emit: f32,
    pdf_rev: f32,
) -> f32 {
    // The camera subpath that goes on from the vertex and hits the emitter.
    let w_light = if merge.camera_goes_on {
        mis(pdf_bsdf / pdf_light)
    } else {
        0.0
    };
    let w_camera = mis(pdf_emit) * (camera.d_vcm + camera.d_vc * mis(pdf_rev) + merge.vm);
    1.0 / (w_light + 1.0 + w_camera)
}

/// The weight of connecting a camera vertex to a stored light vertex (s ≥ 2, t ≥ 2).
/// `camera_to_light` is the area density with which the camera vertex's BSDF would sample the
/// light vertex, `light_to_camera` the reverse, and each `*_rev` the solid-angle density of
/// the vertex's BSDF toward its own subpath's previous vertex, given the connection. With
/// merging, either subpath may also merge at the other's vertex (`merge.vm` on each side).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn weight_connection(
    camera: &SubpathMis,
    light: &SubpathMis,
    merge: &MergeMis,
    camera_to_light: f32,
    camera_rev: f32,
    light_to_camera: f32,
    light_rev: f32,
) -> f32 {
    // The camera subpath that goes on from the camera vertex to the light vertex and beyond.
    let w_light = if merge.camera_goes_on {
        mis(camera_to_light) * (light.d_vcm + light.d_vc * mis(light_rev) + merge.vm)
    } else {
        0.0
    };
    let w_camera = mis(light_to_camera) * (camera.d_vcm + camera.d_vc * mis(camera_rev) + merge.vm);
    1.0 / (w_light + 1.0 + w_camera)
}

/// The weight of connecting a light vertex to the camera (t = 1): `pdf_camera` is the area
/// density with which the camera would sample the vertex (W |cos| / dist²), shared by N light
/// subpaths, and `light_rev` the light vertex's density toward its previous vertex. With
/// merging, a camera subpath may also merge at the vertex (`merge.vm`).
#[inline]
pub fn weight_to_camera(
    light: &SubpathMis,
    merge: &MergeMis,
    pdf_camera: f32,
    n_light_paths: f32,
    light_rev: f32,
) -> f32 {
    // The camera subpaths that take the vertex as their first and connect (d_vcm) or merge
    // (vm) there, and those that go on from it (d_vc).
    let beyond = if merge.camera_goes_on {
        light.d_vc * mis(light_rev)
    } else {
        0.0
    };
    let w_light = mis(pdf_camera / n_light_paths) * (light.d_vcm + beyond + merge.vm);
    1.0 / (w_light + 1.0)
}

/// The weight of the light point itself seen by the camera (s = 1, t = 1), against the camera
/// subpath hitting the emitter there (s = 0): the light point's area density `pdf_area` and the
/// camera's `pdf_camera`.
#[inline]
pub fn weight_light_point_to_camera(pdf_camera: f32, n_light_paths: f32, pdf_area: f32) -> f32 {
    1.0 / (1.0 + mis(pdf_camera / (n_light_paths * pdf_area)))
}

/// The weight of merging a light vertex (a photon) at a camera vertex (vertex merging, Georgiev
/// et al. 2012, eqs. 37-39 of the report): against the connection at the light vertex
/// (`merge.vc` on the light vertex's d_vcm) and the strategies that merge or connect earlier on
/// the light subpath (its d_vm, with `camera_to_light` the camera vertex's solid-angle density
/// toward the photon's previous vertex), and likewise on the camera side (`camera_rev`, the
/// camera vertex's density toward its own previous vertex). The photon is taken as if it had
/// arrived at the camera vertex, which is what merging approximates.
#[inline]
pub fn weight_merge(
    camera: &SubpathMis,
    light: &SubpathMis,
    merge: &MergeMis,
    camera_to_light: f32,
    camera_rev: f32,
) -> f32 {
    let w_light = merge_light_share(light, merge, camera_to_light);
    1.0 / (w_light + 1.0 + merge_camera_share(camera, merge, camera_rev))
}

/// The light side's part of [`weight_merge`]'s denominator: the strategies that connect or
/// merge on the light subpath, relative to merging here. It does not depend on the camera
/// vertex (the photon is taken as arrived there), so the CPU computes it once per photon and
/// iteration ([`PhotonRecord`]).
#[inline]
pub fn merge_light_share(light: &SubpathMis, merge: &MergeMis, camera_to_light: f32) -> f32 {
    // The connection at the camera vertex (d_vcm), and the strategies whose camera subpath
    // goes on to the photon's previous vertex and beyond (d_vm).
    let beyond = if merge.camera_goes_on {
        light.d_vm * mis(camera_to_light)
    } else {
        0.0
    };
    light.d_vcm * merge.vc + beyond
}

/// The camera side's part of [`weight_merge`]'s denominator: the strategies that connect or
/// merge on the camera subpath, relative to merging here. It does not depend on the photon.
#[inline]
pub fn merge_camera_share(camera: &SubpathMis, merge: &MergeMis, camera_rev: f32) -> f32 {
    camera.d_vcm * merge.vc + camera.d_vm * mis(camera_rev)
}

/// The bounce from which BDPT and VCM roulette their light subpaths, with the path tracer's
/// survival probability (`cpu::path::RR_MAX_SURVIVAL`); their camera subpaths, and the light
/// subpaths of light tracing and SPPM, start at the path tracer's `RR_START_BOUNCE` (3). The
/// reason is cost: a light vertex of BDPT or VCM is connected to by every camera vertex of its
/// pixel (a shadow ray each) and merged with, so ending more of the light subpaths that carry
/// little buys more iterations; in light tracing a light vertex costs one splat, in SPPM a grid
/// entry. From bounce 1 rather than 3, vcm's relMSE is 6 % lower on tncg15_room and 5 % on
/// glass_room, for 5 – 15 % more iterations (256x256, 20 s on 2 cores, seeds 11 – 14); from 0 or
/// 2 it is no better. The camera subpaths keep bounce 3: from bounce 1 they gain nothing more,
/// and the merging furnace (`tests/photon_merging.rs`) would no longer tell the merge roulette
/// undivided. Light tracing keeps bounce 3 too: from 1, its batch-means χ² falls below its
/// interval (`tests/standard_error.rs`). The sweeps: docs/journal/2026-11-25_light_roulette.md.
pub const LIGHT_SUBPATH_RR_START_BOUNCE: u32 = 1;

/// τ of the Russian roulette on merge queries of VCM and vcm-full ([`merge_survival`]), as a
/// share of the camera subpath's throughput: 0.1. vcm merges only at a camera subpath's first
/// diffuse vertex, where the bound stays above 0.1 nearly everywhere: it skips 0.2 %, 0.3 % and
/// 1 % of the queries on tncg15_room, glass_room and cornell_box, vcm-full 13 % and 16 % on the
/// first two (256x256, 8 iterations). For vcm at 30 s on 2 cores (256x256, seeds 51 and 52),
/// τ = 0.3 gives the same relMSE as 0.1, τ = 1 1.8 – 3.2x and τ = 3 8 – 18x: more iterations,
/// but the roulette's variance falls on dark pixels, which relMSE weighs most
/// (docs/journal/2026-11-30_merge_queue.md).
pub const MERGE_RR_THRESHOLD: f32 = 0.1;

/// Russian roulette on the merge query of a camera vertex (VCM): the probability of running
/// it. What a query adds is β ρ/π · Σ α_i w_i / (π r² N) over the photons i within r, and
/// every photon's weight w_i = 1 / (w_light,i + 1 + w_camera) is at most 1 / (1 + w_camera),
/// the camera side's share ([`merge_camera_share`]), which is known before the query. So
/// b = max(β ρ) / (1 + w_camera) bounds the query's part of the pixel relative to the light
/// that arrives there: it is small where the camera subpath carries little (deep, after dark
/// surfaces) and where the other strategies take the paths that merging here would (a
/// connection from the previous camera vertex, most of all). A query with b below
/// τ = [`MERGE_RR_THRESHOLD`] runs with probability b / τ and is divided by it, which keeps
/// the estimate unbiased (E[Q 1{u < q} / q] = Q) and adds at most (1/q − 1) Q² of variance.
/// SPPM, whose merges are its only strategy, runs every query (τ = 0). A merge query is not a
/// ray: it reads every grid entry of its buckets (about 460 on tncg15_room at 256x256 with the
/// default radius), and where b is small the other strategies carry the light.
#[inline]
pub fn merge_survival(
    camera: &SubpathMis,
    merge: &MergeMis,
    camera_rev: f32,
    throughput_albedo: f32,
    threshold: f32,
) -> f32 {
    let bound = throughput_albedo / (1.0 + merge_camera_share(camera, merge, camera_rev));
    if bound >= threshold || threshold <= 0.0 {
        1.0
    } else {
        bound / threshold
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// VCM that merges traces fewer camera subpaths behind mirrors and glass than BDPT; VCM
    /// with the radius 0 traces BDPT's number, so that it stays BDPT.
    #[test]
    fn only_vcm_that_merges_takes_fewer_specular_camera_subpaths() {
        let bdpt = specular_camera_subpaths(Method::Bdpt, 0.0);
        assert_eq!(specular_camera_subpaths(Method::Vcm, 0.0), bdpt);
        assert_eq!(specular_camera_subpaths(Method::Bdpt, 0.1), bdpt);
        assert_eq!(specular_camera_subpaths(Method::Sppm, 0.1), bdpt);
        let vcm = specular_camera_subpaths(Method::Vcm, 1e-6);
        assert!(vcm < bdpt, "{vcm} against {bdpt}");
    }
}
