//! The path tracer as a wavefront: [`trace_pixels`] traces a tile's samples eight paths at a
//! time in the SIMD lanes of a [`Slot`], each field of the path's state a row of eight
//! (structure of arrays). Every sample is the path of [`trace_path`](super::path::trace_path) (`path.rs`, the scalar
//! reference and the twin of `shaders/path.wgsl`), with the same arithmetic in the same order,
//! so the image is the same bit for bit; a test below holds it to that.

use super::path::{
    end_bounce, finish_path, shade_hit, start_path, NextEvent, PathState, RR_MAX_SURVIVAL,
    RR_START_BOUNCE,
};
use crate::accel::packet::{intersect_closest_lanes, occluded_all, occluded_lanes, HitLanes};
use crate::film::PixelStats;
use crate::layout::{FlatScene, KIND_DIFFUSE};
use crate::math::geometry::Ray;
use crate::math::lanes::{self, lanes_of, F8, LANES, U8, V8};
use crate::math::sampling::{dim_bsdf, dim_light, Sampler, SamplerKind};
use crate::transport::camera::Camera;
use crate::transport::faults::Faults;
use crate::transport::light::sample_emitter_lanes;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// The samples `first..first + count` of each pixel `(index, x, y)` of `pixels`, added in
/// sample order to its `stats`: [`trace_path`](super::path::trace_path) for every sample, run as a wavefront of eight
/// paths in the SIMD lanes of a [`Slot`], whose state is kept as rows of eight values
/// (structure of arrays, as Mitsuba's wavefronts keep theirs). Each round traces the eight
/// closest-hit rays as one packet straight from the rows ([`intersect_closest_lanes`]), shades
/// the diffuse hits in lanes (steps 3 to 6, [`shade_diffuse_lanes`]) and the others one by one
/// ([`shade_hit`]), traces the diffuse hits' shadow rays as one packet ([`occluded_lanes`]) and
/// adds what they let through. A lane whose path ended adds its sample to its pixel and starts
/// the pixel's next sample, or the next pixel's first, in place (path regeneration, as the
/// shader's `render_pass`), so that nothing is gathered or moved between rounds. Each sample is the
/// same path as `trace_path`'s, with the same arithmetic in the same order, so the image is the
/// same bit for bit (a test below).
#[allow(clippy::too_many_arguments)]
pub fn trace_pixels(
    scene: &FlatScene,
    camera: &Camera,
    pixels: &[(u32, u32, u32)],
    kind: SamplerKind,
    seed: u32,
    first: u32,
    count: u32,
    light_samples: u32,
    faults: Faults,
    stats: &mut [PixelStats],
    rays: &mut u64,
) {
    let samples = |_| first..first + count;
    trace_pixel_samples(
        scene,
        camera,
        pixels,
        samples,
        kind,
        seed,
        light_samples,
        faults,
        stats,
        rays,
    );
}

/// [`trace_pixels`] with each pixel's own samples: `samples(p)` for `pixels[p]` (adaptive
/// sampling's runs, `crate::render::adaptive`), in the same wavefront.
#[allow(clippy::too_many_arguments)]
pub fn trace_pixel_samples(
    scene: &FlatScene,
    camera: &Camera,
    pixels: &[(u32, u32, u32)],
    samples: impl Fn(usize) -> std::ops::Range<u32>,
    kind: SamplerKind,
    seed: u32,
    light_samples: u32,
    faults: Faults,
    stats: &mut [PixelStats],
    rays: &mut u64,
) {
    assert_eq!(pixels.len(), stats.len());
    let start = |slot: &mut Slot, l: usize, p: usize, sample: u32| {
        let (index, x, y) = pixels[p];
        let path = start_path(camera, x, y, &Sampler::of(kind, seed, index, sample));
        slot.set_path(l, &path);
        slot.pixel[l] = p;
        slot.stream.as_mut_array()[l] = index;
        slot.sample.as_mut_array()[l] = sample;
        slot.live |= 1 << l;
    };
    let mut slot = Slot::default();
    // The next of the tile's pixels no lane has taken yet, past those with no samples.
    let mut next = 0;
    let take_next = |slot: &mut Slot, l: usize, next: &mut usize| {
        while *next < pixels.len() {
            let p = *next;
            *next += 1;
            let range = samples(p);
            if !range.is_empty() {
                start(slot, l, p, range.start);
                return;
            }
        }
    };
    for l in 0..LANES {
        take_next(&mut slot, l, &mut next);
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
            let sampler = Sampler::of(
                kind,
                seed,
                slot.stream.as_array()[l],
                slot.sample.as_array()[l],
            );
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
        let lit = shade_diffuse_lanes(scene, kind, seed, &hits, diffuse, &mut slot, faults);
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
            if sample < samples(p).end {
                start(&mut slot, l, p, sample);
            } else {
                take_next(&mut slot, l, &mut next);
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
/// one shadow ray, in SIMD lanes ([`crate::math::lanes`]): lane l shades its path at `hits[l]` with
/// the numbers of its stream, bit for bit what `shade_hit` does (a test below), and the other
/// lanes are left as they are. Step 3 adds nothing at a surface that does not emit, so it is
/// left out.
#[inline]
fn shade_diffuse_lanes(
    scene: &FlatScene,
    kind: SamplerKind,
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
        kind,
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
        kind,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::path::trace_path;
    use crate::scene::Scene;

    /// The paths `trace_pixels` traces together, eight to a packet and their diffuse hits
    /// eight to a batch of lanes, are `trace_path`'s one at a time, bit for bit: every pixel's
    /// sums of a 13x11 block (not a multiple of the packet), samples 3 to 10, on the rooms with
    /// mirrors, glass and spheres and on the all-diffuse box, with one shadow ray a vertex (the
    /// lanes) and with two (one by one), with the grey-indirect fault, whose snapshot must
    /// come after the vertex's next-event light, and with a maximum depth and a darkened
    /// specular bounce, which the lanes' roulette and weight must apply as `take_bsdf_sample`;
    /// and with both samplers.
    #[test]
    fn the_wavefront_traces_each_samples_own_path_bit_for_bit() {
        for name in ["tncg15_room", "glass_room", "cornell_box"] {
            let path = format!("{}/scenes/{name}.json", env!("CARGO_MANIFEST_DIR"));
            let scene = Scene::load(std::path::Path::new(&path)).expect("scene");
            let flat = FlatScene::build(&scene, crate::accel::bvh::Traversal::Cpu);
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
            for (light_samples, faults, kind) in [
                (1, Faults::NONE, SamplerKind::Independent),
                (2, Faults::NONE, SamplerKind::Independent),
                (1, grey, SamplerKind::Independent),
                (1, short, SamplerKind::Independent),
                (1, Faults::NONE, SamplerKind::Sobol),
                (2, Faults::NONE, SamplerKind::Sobol),
            ] {
                let mut together = vec![PixelStats::default(); pixels.len()];
                let (mut rays_together, mut rays_alone) = (0, 0);
                trace_pixels(
                    &flat,
                    &camera,
                    &pixels,
                    kind,
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
                        let sampler = Sampler::of(kind, 9, index, s);
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
                        "{name}, pixel ({x}, {y}), {light_samples} light samples, {faults:?}, {kind}"
                    );
                }
                assert_eq!(rays_together, rays_alone, "{name}: rays counted");
            }
        }
    }
}
