//! The path integrator: one camera sample's radiance estimate, as an iterative loop.
//!
//! `shaders/path.wgsl` is this function again, with the same names, the same steps in the same
//! order and the same step comments; read the two side by side. One difference of schedule: the
//! shader traces step 4's shadow ray where it is made, while here `shade_hit` hands it out
//! ([`NextEvent`]) so that [`trace_pixels`] can trace a round's shadow rays together; its light
//! is added before the next bounce's, the same sum in the same order. And `trace_pixels` keeps
//! eight paths in SIMD lanes, each field a row of eight (a `Slot`), and shades their diffuse
//! hits in those lanes (`shade_diffuse_lanes`): `shade_hit`'s arithmetic, operation for
//! operation, so each path is the same bit for bit.
//!
//! The estimator is unidirectional path tracing with next-event estimation and multiple
//! importance sampling (Veach's thesis, ch. 9): at each diffuse vertex, direct light is
//! estimated twice, once by sampling a point on an emitter and once by the BSDF-sampled
//! continuation ray hitting an emitter, and the two are combined with the power heuristic.
//! Specular vertices (mirror, glass) cannot be reached by light sampling, so emission found
//! after them is counted in full. Russian roulette ends paths without bias; there is no
//! maximum depth.

use crate::bsdf::{sample_bsdf, BsdfSample, Transport};
use crate::bvh::{intersect_closest, occluded};
use crate::camera::Camera;
use crate::film::PixelStats;
use crate::flat::{FlatScene, KIND_DIFFUSE, KIND_EMITTER};
use crate::geometry::{offset_ray_origin, Ray, SurfaceHit};
use crate::lanes::{self, lanes_of, F8, LANES, U8, V8};
use crate::light::{area_to_solid_angle, emitter_pdf_area, sample_emitter, sample_emitter_lanes};
use crate::packet::{intersect_closest_lanes, occluded_all, occluded_lanes, HitLanes};
use crate::sampling::{
    dim_bsdf, dim_light, dim_light_extra, power_heuristic, Sampler, DIM_CAMERA, MAX_LIGHT_SAMPLES,
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

/// Test-only changes to the integrator, for showing that the statistical tests reject a wrong
/// renderer. The production path uses `Faults::NONE`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Faults {
    /// Multiplies the throughput at every mirror and glass bounce (1 when correct).
    pub specular_scale: f32,
    /// Ends every path after this many bounces (`u32::MAX` when correct: no maximum depth).
    pub max_bounces: u32,
    /// Replaces the light a path gathers after its first diffuse bounce by its grey (the mean
    /// of its three channels): a renderer whose indirect light, and so its shadows, lose colour
    /// (false when correct).
    pub grey_indirect: bool,
    /// Light tracing and BDPT: splats with a camera importance that lacks one cos θ factor,
    /// 1 / (A_pix cos²θ) (false when correct).
    pub importance_missing_cos: bool,
    /// SPPM and VCM: merges counted with the kernel of the 3-D ball, 1 / (4/3 π r³), instead
    /// of the disk's 1 / (π r²) (false when correct).
    pub merge_kernel_ball: bool,
    /// Light tracing, BDPT and the merging methods: a subpath goes on past a hit whose area
    /// density vanishes in f32 (`subpath::density_vanishes`) instead of ending there, and its
    /// MIS quantities become NaN (false when correct).
    pub continue_at_vanishing_density: bool,
    /// VCM: merge queries rouletted (`subpath::merge_survival`) but not divided by their
    /// survival probability (false when correct).
    pub merge_rr_undivided: bool,
    /// BDPT (the CPU): the light that reaches a diffuse vertex from a planar mirror is
    /// taken by next-event estimation through the mirror and also, with the weights of the
    /// other strategies, by those (the emission a camera subpath meets in the mirror, the
    /// light subpath's vertices from that diffuse vertex on): counted about twice (false when
    /// correct).
    pub mirror_light_twice: bool,
    /// vcm: merges within the iteration's radius everywhere, also where another surface is
    /// nearer than that (`merging::local_radius`): still consistent, but the room's edges come
    /// out darker at a given radius (false when correct).
    pub merge_ignores_clearance: bool,
}

impl Faults {
    pub const NONE: Faults = Faults {
        specular_scale: 1.0,
        max_bounces: u32::MAX,
        grey_indirect: false,
        importance_missing_cos: false,
        merge_kernel_ball: false,
        continue_at_vanishing_density: false,
        merge_rr_undivided: false,
        mirror_light_twice: false,
        merge_ignores_clearance: false,
    };
}

impl Default for Faults {
    fn default() -> Self {
        Faults::NONE
    }
}

/// The radiance arriving at pixel (x, y) along one camera sample's path, with `light_samples`
/// shadow rays at every diffuse vertex (1 is the default, at most `MAX_LIGHT_SAMPLES`; see
/// step 4). `rays` counts the rays traced (closest-hit and shadow), for the benchmark's rays/s.
///
/// The path is started ([`start_path`]), advanced one bounce at a time ([`path_bounce`]) until
/// it ends, and finished ([`finish_path`]). [`trace_pixels`] runs the same steps for many
/// pixels at once, their rays in packets; the shader's `render` hands a lane whose path ended
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

/// The samples `first..first + count` of each pixel `(index, x, y)` of `pixels`, added in
/// sample order to its `stats`: [`trace_path`] for every sample, run as a wavefront of eight
/// paths in the SIMD lanes of a [`Slot`], whose state is kept as rows of eight values
/// (structure of arrays, as Mitsuba's wavefronts keep theirs). Each round traces the eight
/// closest-hit rays as one packet straight from the rows ([`intersect_closest_lanes`]), shades
/// the diffuse hits in lanes (steps 3 to 6, [`shade_diffuse_lanes`]) and the others one by one
/// ([`shade_hit`]), traces the diffuse hits' shadow rays as one packet ([`occluded_lanes`]) and
/// adds what they let through. A lane whose path ended adds its sample to its pixel and starts
/// the pixel's next sample, or the next pixel's first, in place (path regeneration, as the
/// shader's `render`), so that nothing is gathered or moved between rounds. Each sample is the
/// same path as `trace_path`'s, with the same arithmetic in the same order, so the image is the
/// same bit for bit (a test below).
#[allow(clippy::too_many_arguments)]
pub fn trace_pixels(
    scene: &FlatScene,
    camera: &Camera,
    pixels: &[(u32, u32, u32)],
    seed: u32,
    first: u32,
    count: u32,
    light_samples: u32,
    faults: Faults,
    stats: &mut [PixelStats],
    rays: &mut u64,
) {
    assert_eq!(pixels.len(), stats.len());
    if count == 0 {
        return;
    }
    let end = first + count;
    let start = |slot: &mut Slot, l: usize, p: usize, sample: u32| {
        let (index, x, y) = pixels[p];
        let path = start_path(camera, x, y, &Sampler::new(seed, index, sample));
        slot.set_path(l, &path);
        slot.pixel[l] = p;
        slot.stream.as_mut_array()[l] = index;
        slot.sample.as_mut_array()[l] = sample;
        slot.live |= 1 << l;
    };
    let mut slot = Slot::default();
    // The next of the tile's pixels no lane has taken yet.
    let mut next = 0;
    for l in 0..LANES.min(pixels.len()) {
        start(&mut slot, l, next, first);
        next += 1;
    }
    // The shadow rays of the hits shaded one by one, each with its lane.
    let (mut events, mut event_lanes, mut shadow_rays, mut blocked) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    while slot.live != 0 {
        // Step 2 - closest hit, the eight rays as one packet.
        let hits = intersect_closest_lanes(scene, (&slot.o, &slot.d), slot.live);
        *rays += u64::from(slot.live.count_ones());

        // Steps 3 to 6 at each hit: diffuse hits with one shadow ray in lanes, the others one
        // by one; the shadow rays of step 4 wait to be traced together.
        events.clear();
        event_lanes.clear();
        // A miss ends the path: nothing is outside the scene.
        let mut ended = slot.live & !hits.hit;
        let kinds = lanes::uints(|l| scene.materials[hits.material[l] as usize].kind);
        let diffuse = if light_samples <= 1 {
            slot.live & hits.hit & kinds.simd_eq(U8::splat(KIND_DIFFUSE)).to_bitmask()
        } else {
            0
        };
        for l in lanes_of(slot.live & hits.hit & !diffuse) {
            let hit = hits.get(l);
            let mut path = slot.path(l);
            let sampler = Sampler::new(seed, slot.stream.as_array()[l], slot.sample.as_array()[l]);
            let on = shade_hit(
                scene,
                &mut path,
                &hit,
                &sampler,
                light_samples,
                faults,
                &mut events,
            );
            slot.set_path(l, &path);
            event_lanes.resize(events.len(), l);
            ended |= u32::from(!on) << l;
        }
        let lit = shade_diffuse_lanes(scene, seed, &hits, diffuse, &mut slot, faults);
        ended |= diffuse & !lit.going_on;

        let blocked_lanes = occluded_lanes(scene, (&lit.origin, &lit.to_light), lit.clear);
        *rays += u64::from(lit.clear.count_ones());
        shadow_rays.clear();
        shadow_rays.extend(events.iter().map(|e: &NextEvent| e.ray));
        blocked.resize(events.len(), false);
        occluded_all(scene, &shadow_rays, &mut blocked);
        *rays += events.len() as u64;

        // Each path takes its unblocked shadow rays' light, in order, and ends its bounce.
        let unblocked = lanes::mask(lit.clear & !blocked_lanes);
        slot.radiance = slot
            .radiance
            .select_where(unblocked, &slot.radiance.add(&lit.value));
        for ((&l, event), &b) in event_lanes.iter().zip(&events).zip(&blocked) {
            if !b {
                slot.radiance
                    .set_lane(l, slot.radiance.lane(l) + event.value);
            }
        }
        if faults.grey_indirect {
            for l in lanes_of(slot.live & hits.hit) {
                let mut path = slot.path(l);
                end_bounce(&mut path, faults);
                slot.before_indirect[l] = path.before_indirect;
            }
        }

        // A path that ended adds its sample to its pixel, and its lane takes the pixel's next
        // sample, or the next pixel's first.
        for l in lanes_of(ended) {
            let p = slot.pixel[l];
            stats[p].add(finish_path(&slot.path(l)));
            let sample = slot.sample.as_array()[l] + 1;
            slot.live &= !(1 << l);
            if sample < end {
                start(&mut slot, l, p, sample);
            } else if next < pixels.len() {
                start(&mut slot, l, next, first);
                next += 1;
            }
        }
    }
}

/// Eight camera samples' paths in SIMD lanes, each of [`PathState`]'s fields a row of eight
/// (structure of arrays): lane l is the path of sample `sample[l]` of the tile's pixel
/// `pixel[l]` (whose stream is `stream[l]`), in flight where `live` has bit l.
#[derive(Clone, Copy, Debug, Default)]
struct Slot {
    o: V8,
    d: V8,
    radiance: V8,
    throughput: V8,
    eta_scale: F8,
    bsdf_pdf: F8,
    bounce: U8,
    before_indirect: [Option<Vec3>; LANES],
    pixel: [usize; LANES],
    stream: U8,
    sample: U8,
    live: u32,
}

impl Slot {
    /// Lane `l`'s path.
    #[inline]
    fn path(&self, l: usize) -> PathState {
        PathState {
            ray: Ray {
                o: self.o.lane(l),
                d: self.d.lane(l),
            },
            radiance: self.radiance.lane(l),
            throughput: self.throughput.lane(l),
            eta_scale: self.eta_scale.as_array()[l],
            bsdf_pdf: self.bsdf_pdf.as_array()[l],
            bounce: self.bounce.as_array()[l],
            before_indirect: self.before_indirect[l],
        }
    }

    /// Lane `l`'s path set to `path`.
    #[inline]
    fn set_path(&mut self, l: usize, path: &PathState) {
        self.o.set_lane(l, path.ray.o);
        self.d.set_lane(l, path.ray.d);
        self.radiance.set_lane(l, path.radiance);
        self.throughput.set_lane(l, path.throughput);
        self.eta_scale.as_mut_array()[l] = path.eta_scale;
        self.bsdf_pdf.as_mut_array()[l] = path.bsdf_pdf;
        self.bounce.as_mut_array()[l] = path.bounce;
        self.before_indirect[l] = path.before_indirect;
    }
}

/// What [`shade_diffuse_lanes`] hands back: each lit lane's shadow ray (from `origin` along
/// `to_light`, the lanes `clear`) and the light it adds where nothing blocks it, and the lanes
/// whose paths go on.
struct LitLanes {
    origin: V8,
    to_light: V8,
    value: V8,
    clear: u32,
    going_on: u32,
}

/// Steps 3 to 6 of [`shade_hit`] at the diffuse hits of the slot's lanes `lanes`, each with
/// one shadow ray, in SIMD lanes ([`crate::lanes`]): lane l shades its path at `hits[l]` with
/// the numbers of its stream, bit for bit what `shade_hit` does (a test below), and the other
/// lanes are left as they are. Step 3 adds nothing at a surface that does not emit, so it is
/// left out.
#[inline]
fn shade_diffuse_lanes(
    scene: &FlatScene,
    seed: u32,
    hits: &HitLanes,
    lanes: u32,
    slot: &mut Slot,
    faults: Faults,
) -> LitLanes {
    if lanes == 0 {
        // No diffuse hit this round: nothing to shade (and no emitter row is read).
        return LitLanes {
            origin: V8::default(),
            to_light: V8::default(),
            value: V8::default(),
            clear: 0,
            going_on: 0,
        };
    }
    let (p, p_err, n) = (&hits.p, &hits.p_err, &hits.n);
    let wo = slot.d.neg();
    let albedo = V8::gather_from(&scene.materials, U8::new(hits.material), 0);
    let facing = n.neg_where(n.dot(&wo).simd_lt(F8::ZERO));
    let bounce = slot.bounce.as_array();

    // Step 4 - next-event estimation, one light sample (`shade_hit`'s step 4 with N = 1).
    let u_light = lanes::draw4(
        seed,
        slot.stream,
        slot.sample,
        lanes::uints(|l| dim_light(bounce[l])),
    );
    let ls = sample_emitter_lanes(scene, u_light[0], u_light[1], u_light[2], lanes);
    let (ls_p, ls_p_err, ls_n, ls_le) = (ls.p, ls.p_err, ls.n, ls.le);
    let to_light = ls_p.sub(p);
    let dist2 = to_light.dot(&to_light);
    let wi = to_light.div(dist2.sqrt());
    let cos_s = facing.dot(&wi);
    let cos_l = lanes::neg(ls_n.dot(&wi));
    let origin = lanes::offset_ray_origin(p, p_err, n, &wi);
    let light_point = lanes::offset_ray_origin(&ls_p, &ls_p_err, &ls_n, &wi.neg());
    let light_pdf = ls.pdf_area * dist2 / cos_l.abs();
    let f = albedo.scale(F8::splat(FRAC_1_PI));
    // The power heuristic against BSDF sampling, as `power_heuristic`.
    let (f2, g) = (light_pdf * light_pdf, cos_s * F8::splat(FRAC_1_PI));
    let sum = f2 + g * g;
    let w = sum.simd_gt(F8::ZERO).select(f2 / sum, F8::ZERO);
    let value = slot
        .throughput
        .mul(&f)
        .mul(&ls_le)
        .scale(cos_s * w / light_pdf);
    let clear = lanes
        & (cos_s.simd_gt(F8::ZERO) & cos_l.simd_gt(F8::ZERO) & dist2.simd_gt(F8::ZERO))
            .to_bitmask();

    // Step 5 - scattering: a cosine-weighted direction about the side wo lies on
    // (`sample_bsdf`'s diffuse lobe, whose weight is the albedo, its pdf cos θ / π).
    let u_bsdf = lanes::draw4(
        seed,
        slot.stream,
        slot.sample,
        lanes::uints(|l| dim_bsdf(bounce[l])),
    );
    let local = lanes::sample_cosine_hemisphere(u_bsdf[0], u_bsdf[1]);
    let (t, b) = lanes::orthonormal_basis(&facing);
    let wi = t
        .scale(local.x)
        .add(&b.scale(local.y))
        .add(&facing.scale(local.z));
    let pdf = local.z * F8::splat(FRAC_1_PI);
    let ray_o = lanes::offset_ray_origin(p, p_err, n, &wi);

    // `take_bsdf_sample` in lanes: the throughput takes the weight (and the specular fault
    // where the pdf is 0), the eta scale stays (its factor is 1), the next ray leaves where
    // the throughput is not all 0, then step 6's roulette.
    let shaded = lanes::mask(lanes);
    let mut throughput = slot.throughput.mul(&albedo);
    throughput = throughput.select_where(
        pdf.simd_eq(F8::ZERO),
        &throughput.scale(F8::splat(faults.specular_scale)),
    );
    let carries = shaded & !throughput.max_element().simd_le(F8::ZERO);
    slot.o = slot.o.select_where(carries, &ray_o);
    slot.d = slot.d.select_where(carries, &wi);
    // Step 6 - Russian roulette (`take_bsdf_sample`): from bounce RR_START_BOUNCE on,
    // continue with probability q = min(max(throughput) · eta_scale, 0.95) and divide by q.
    let rouletted = slot.bounce.simd_gt(U8::splat(RR_START_BOUNCE - 1));
    let rouletted: F8 = bytemuck::cast(rouletted);
    let q = throughput.max_element() * slot.eta_scale;
    let q = q
        .simd_lt(F8::splat(RR_MAX_SURVIVAL))
        .select(q, F8::splat(RR_MAX_SURVIVAL));
    let survives = !u_light[3].simd_ge(q);
    let divided = carries & rouletted & survives;
    throughput = throughput.select_where(divided, &throughput.div(q));
    let goes_on = carries & (!rouletted | survives);
    slot.throughput = slot.throughput.select_where(shaded, &throughput);
    slot.bsdf_pdf = shaded.select(pdf, slot.bsdf_pdf);
    let goes_on_bits = goes_on.to_bitmask();
    slot.bounce = bytemuck::cast::<F8, U8>(goes_on).select(slot.bounce + U8::splat(1), slot.bounce);
    let under_max = slot.bounce.simd_lt(U8::splat(faults.max_bounces));
    LitLanes {
        origin,
        to_light: light_point.sub(&origin),
        value,
        clear,
        going_on: goes_on_bits & bytemuck::cast::<U8, F8>(under_max).to_bitmask(),
    }
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
            let to_light = ls.p - hit.p;
            let dist2 = to_light.length_squared();
            let wi = to_light / dist2.sqrt();
            let cos_s = n_facing.dot(wi);
            let cos_l = -ls.n.dot(wi);
            if cos_s > 0.0 && cos_l > 0.0 && dist2 > 0.0 {
                let origin = offset_ray_origin(hit.p, hit.p_err, hit.n, wi);
                let light_point = offset_ray_origin(ls.p, ls.p_err, ls.n, -wi);
                let shadow = Ray {
                    o: origin,
                    d: light_point - origin,
                };
                let light_pdf = area_to_solid_angle(ls.pdf_area, dist2, cos_l);
                let f = albedo * FRAC_1_PI;
                let w = power_heuristic(n_light * light_pdf, cos_s * FRAC_1_PI);
                events.extend([NextEvent {
                    ray: shadow,
                    value: path.throughput * f * ls.le * (cos_s * w / (n_light * light_pdf)),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    /// The paths `trace_pixels` traces together, eight to a packet and their diffuse hits
    /// eight to a batch of lanes, are `trace_path`'s one at a time, bit for bit: every pixel's
    /// sums of a 13x11 block (not a multiple of the packet), samples 3 to 10, on the rooms with
    /// mirrors, glass and spheres and on the all-diffuse box, with one shadow ray a vertex (the
    /// lanes) and with two (one by one), with the grey-indirect fault, whose snapshot must
    /// come after the vertex's next-event light, and with a maximum depth and a darkened
    /// specular bounce, which the lanes' roulette and weight must apply as `take_bsdf_sample`.
    #[test]
    fn the_wavefront_traces_each_samples_own_path_bit_for_bit() {
        for name in ["tncg15_room", "glass_room", "cornell_box"] {
            let path = format!("{}/scenes/{name}.json", env!("CARGO_MANIFEST_DIR"));
            let scene = Scene::load(std::path::Path::new(&path)).expect("scene");
            let flat = FlatScene::build(&scene);
            let camera = Camera::new(&scene.desc.camera, 64, 64);
            let pixels: Vec<(u32, u32, u32)> = (20..31)
                .flat_map(|y| (30..43).map(move |x| (y * 64 + x, x, y)))
                .collect();
            let grey = Faults {
                grey_indirect: true,
                ..Faults::NONE
            };
            let short = Faults {
                max_bounces: 4,
                specular_scale: 0.5,
                ..Faults::NONE
            };
            for (light_samples, faults) in
                [(1, Faults::NONE), (2, Faults::NONE), (1, grey), (1, short)]
            {
                let mut together = vec![PixelStats::default(); pixels.len()];
                let (mut rays_together, mut rays_alone) = (0, 0);
                trace_pixels(
                    &flat,
                    &camera,
                    &pixels,
                    9,
                    3,
                    8,
                    light_samples,
                    faults,
                    &mut together,
                    &mut rays_together,
                );
                for (&(index, x, y), got) in pixels.iter().zip(&together) {
                    let mut want = PixelStats::default();
                    for s in 3..11 {
                        let sampler = Sampler::new(9, index, s);
                        want.add(trace_path(
                            &flat,
                            &camera,
                            x,
                            y,
                            &sampler,
                            light_samples,
                            faults,
                            &mut rays_alone,
                        ));
                    }
                    assert_eq!(
                        *got, want,
                        "{name}, pixel ({x}, {y}), {light_samples} light samples, {faults:?}"
                    );
                }
                assert_eq!(rays_together, rays_alone, "{name}: rays counted");
            }
        }
    }
}
