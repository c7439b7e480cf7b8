//! BDPT's MIS weights are a partition of unity: for a path x0 (the pinhole) … xk (on an
//! emitter), the weights that the renderer's recursive quantities give each strategy that can
//! make the path sum to 1, whatever the path's length and whatever mirrors and glass it passes
//! (Veach's thesis, eq. 9.4: that sum being 1 is what makes the combination unbiased). The
//! paths whose light end is a light point, a planar mirror and a diffuse vertex are next-event
//! estimation's through the mirror alone (`planar_mirror`: the renderer skips the other
//! strategies there); the recursive quantities still weigh the other strategies as here, and
//! `tests/bdpt_references.rs` checks that partition against path tracing's references.
//!
//! The paths are random walks through the reference scenes (tncg15_room with its mirror wall and
//! mirror sphere, glass_room with its glass spheres, cornell_box; pixels that see a mirror or
//! glass trace n_c = 5 camera subpaths per iteration, the others 1), and through a white furnace
//! (every wall an emitter that also reflects) cut at lengths up to 60 bounces, far longer than
//! any light subpath the renderer has ever stored. Each strategy's weight is computed by
//! replaying its two subpaths over the path's vertices with the renderer's own functions
//! (`SubpathMis::camera`, `light`, `at_hit`, `after_diffuse`, `after_specular` and the
//! `weight_*` of `src/transport/subpath.rs`), with the densities the renderer computes (cosine sampling,
//! the importance, the emitter table): the strategies that can make the path are s = 0 if xk is
//! an emitter seen from its front, s = 1 (next-event estimation) and 2 ≤ s ≤ k − 1 (connections)
//! where both ends of the connecting edge are diffuse, and s = k (t = 1, splat) where x1 is.
//!
//! With merging (VCM), the strategies that merge at each diffuse vertex x1 … x(k−1) join the
//! sum (`weight_merge`), and every weight carries the iteration's constants (`MergeMis`) for a
//! merge radius r; the same property holds, and leaving the merges out is rejected.
//!
//! Statistic: none needed, the property is exact up to f32 rounding: |Σw − 1| < 1e-4 for every
//! path. The planted error is one strategy (next-event estimation) left out of the sum, which a
//! renderer whose weights forgot that strategy in its denominators is equivalent to; it is
//! rejected on the first paths.

use crate::common::*;
use glam::Vec3;
use hexray::accel::bvh::intersect_closest;
use hexray::layout::{FlatScene, KIND_EMITTER};
use hexray::math::geometry::{offset_ray_origin, Ray};
use hexray::math::sampling::Sampler;
use hexray::transport::bsdf::is_diffuse;
use hexray::transport::bsdf::{sample_bsdf, Transport};
use hexray::transport::camera::Camera;
use hexray::transport::light::emitter_pdf_area;
use hexray::transport::method::Method;
use hexray::transport::subpath::{
    camera_subpaths, specular_camera_subpaths, specular_pixels, weight_connection, weight_emission,
    weight_light_point_to_camera, weight_merge, weight_next_event, weight_to_camera, MergeMis,
    SubpathMis,
};
use std::f32::consts::FRAC_1_PI;

/// Image size: N = 64 · 64 light subpaths compete through t = 1.
const SIZE: u32 = 64;

/// A vertex of a path: where, its unit geometric normal, and what the renderer can do there.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    p: Vec3,
    n: Vec3,
    diffuse: bool,
    /// The triangle, where the vertex is on an emitter's front (s = 0 and the light point).
    emitter: Option<u32>,
}

/// |cos| between a vertex's normal and the direction toward another point.
fn cos_to(v: &Vertex, other: Vec3) -> f32 {
    v.n.dot((other - v.p).normalize()).abs()
}

/// A random walk from the camera through pixel `index`, by BSDF sampling, of `length` bounces or
/// until it leaves the scene; returns the vertices x1 … (x0 is the eye).
fn walk(scene: &FlatScene, camera: &Camera, index: u32, length: usize) -> Vec<Vertex> {
    let sampler = Sampler::new(99, index, 0);
    let u = sampler.draw4(0);
    let mut ray = camera.ray(index % SIZE, (index / SIZE) % SIZE, u[0], u[1]);
    let mut path = Vec::new();
    for bounce in 0..length {
        let Some(hit) = intersect_closest(scene, &ray, f32::MAX) else {
            break;
        };
        let m = scene.materials[hit.material as usize];
        let front = m.kind == KIND_EMITTER && hit.n.dot(-ray.d) > 0.0;
        path.push(Vertex {
            p: hit.p,
            n: hit.n,
            diffuse: is_diffuse(&m),
            emitter: front.then_some(hit.prim),
        });
        if m.kind == KIND_EMITTER && !is_diffuse(&m) {
            break;
        }
        let bs = sample_bsdf(
            &m,
            hit.n,
            -ray.d,
            sampler.draw4(1 + bounce as u32),
            Transport::Radiance,
        );
        ray = Ray {
            o: offset_ray_origin(hit.p, hit.p_err, hit.n, bs.wi),
            d: bs.wi,
        };
    }
    path
}

/// Replays a subpath over `points[0..]` (its first point is the camera's eye or the light
/// point) up to and including vertex `last`, scattering at every vertex before it toward the
/// next: the quantities the renderer holds at `last`.
fn replay(
    start: SubpathMis,
    points: &[Vertex],
    eye: Option<Vec3>,
    last: usize,
    merge: &MergeMis,
) -> SubpathMis {
    let mut mis = start;
    let position = |i: usize| {
        if i == 0 {
            eye.unwrap_or(points[0].p)
        } else {
            points[i].p
        }
    };
    for j in 1..=last {
        let (prev, here) = (position(j - 1), &points[j]);
        mis.at_hit((here.p - prev).length_squared(), cos_to(here, prev));
        if j < last {
            let next = points[j + 1].p;
            let cos_out = cos_to(here, next);
            if here.diffuse {
                mis.after_diffuse(
                    cos_out,
                    cos_out * FRAC_1_PI,
                    cos_to(here, prev) * FRAC_1_PI,
                    merge,
                );
            } else {
                mis.after_specular(cos_out);
            }
        }
    }
    mis
}

/// Strategies are numbered by s for the connections; a merge at x_j is number MERGE + j.
const MERGE: usize = 1000;

/// The weights of every strategy that can make the path x0 = eye, x1.. = `path` (whose last
/// vertex is on an emitter's front), as (s, weight); the pixel the path passes traces `n_c`
/// camera subpaths per iteration; `merge` holds merging's constants (`MergeMis::NONE`: BDPT).
fn strategy_weights(
    scene: &FlatScene,
    camera: &Camera,
    path: &[Vertex],
    n_c: f32,
    merge: &MergeMis,
) -> Vec<(usize, f32)> {
    let n_paths = (SIZE * SIZE) as f32;
    let eye = Vec3::from(camera.eye);
    let k = path.len();
    // Camera points: x0 = the eye (a placeholder vertex), x1..xk.
    let mut xs = vec![Vertex {
        p: eye,
        n: Vec3::Z,
        diffuse: false,
        emitter: None,
    }];
    xs.extend_from_slice(path);
    // Light points: y0 = xk, y1 = x(k-1), ..., y(k-1) = x1.
    let ys: Vec<Vertex> = path.iter().rev().copied().collect();
    let light_tri = path[k - 1]
        .emitter
        .expect("the path ends on an emitter's front");
    let pdf_area = emitter_pdf_area(scene, light_tri);
    let camera_start = {
        let d = (xs[1].p - eye).normalize();
        SubpathMis::camera(
            n_paths,
            n_c * camera.importance(d.dot(Vec3::from(camera.forward))),
        )
    };
    let light_start = |toward: Vec3| {
        let cos = cos_to(&ys[0], toward);
        SubpathMis::light(pdf_area, cos * FRAC_1_PI, cos, merge)
    };
    // The camera's area density of x1, n_c subpaths' worth.
    let pdf_camera_x1 = {
        let r = camera.raster(xs[1].p).expect("x1 is in view");
        n_c * r.importance * cos_to(&xs[1], eye) / r.dist2
    };
    let mut weights = Vec::new();

    // s = 0: the camera subpath x0..xk hits the emitter.
    let at_light = replay(camera_start, &xs, Some(eye), k, merge);
    let cos_l = cos_to(&xs[k], xs[k - 1].p);
    weights.push((0, weight_emission(&at_light, pdf_area, cos_l * FRAC_1_PI)));

    // s = 1: next-event estimation from x(k-1) to xk (k >= 2), or the light point seen by the
    // camera (k = 1).
    if k == 1 {
        weights.push((
            1,
            weight_light_point_to_camera(pdf_camera_x1, n_paths, pdf_area),
        ));
    } else if xs[k - 1].diffuse {
        let mis = replay(camera_start, &xs, Some(eye), k - 1, merge);
        let (x, l) = (&xs[k - 1], &xs[k]);
        let dist2 = (l.p - x.p).length_squared();
        let (cos_s, cos_l) = (cos_to(x, l.p), cos_to(l, x.p));
        let w = weight_next_event(
            &mis,
            merge,
            cos_s * FRAC_1_PI,
            pdf_area * dist2 / cos_l,
            cos_l * FRAC_1_PI * cos_s / dist2,
            cos_to(x, xs[k - 2].p) * FRAC_1_PI,
        );
        weights.push((1, w));
    }

    // 2 <= s <= k - 1: camera vertex x(t-1) connected to light vertex y(s-1) = x(t).
    for s in 2..k {
        let t = k + 1 - s;
        let (c, l) = (&xs[t - 1], &xs[t]);
        if !c.diffuse || !l.diffuse {
            continue;
        }
        let camera_mis = replay(camera_start, &xs, Some(eye), t - 1, merge);
        let light_mis = replay(light_start(ys[1].p), &ys, None, s - 1, merge);
        let dist2 = (l.p - c.p).length_squared();
        let (cos_c, cos_lv) = (cos_to(c, l.p), cos_to(l, c.p));
        let w = weight_connection(
            &camera_mis,
            &light_mis,
            merge,
            cos_c * FRAC_1_PI * cos_lv / dist2,
            cos_to(c, xs[t - 2].p) * FRAC_1_PI,
            cos_lv * FRAC_1_PI * cos_c / dist2,
            cos_to(l, xs[t + 1].p) * FRAC_1_PI,
        );
        weights.push((s, w));
    }

    // s = k (t = 1): light vertex y(k-1) = x1 splatted to the camera (k >= 2).
    if k >= 2 && xs[1].diffuse {
        let light_mis = replay(light_start(ys[1].p), &ys, None, k - 1, merge);
        let w = weight_to_camera(
            &light_mis,
            merge,
            pdf_camera_x1,
            n_paths,
            cos_to(&xs[1], xs[2].p) * FRAC_1_PI,
        );
        weights.push((k, w));
    }

    // Merges (VCM): at a diffuse x_j, 1 <= j <= k - 1, the camera subpath x0..x_j meets the
    // light subpath y0..y(k-j) = x_j, whose previous vertex is x(j+1).
    if *merge != MergeMis::NONE {
        for j in 1..k {
            if !xs[j].diffuse {
                continue;
            }
            let camera_mis = replay(camera_start, &xs, Some(eye), j, merge);
            let light_mis = replay(light_start(ys[1].p), &ys, None, k - j, merge);
            let w = weight_merge(
                &camera_mis,
                &light_mis,
                merge,
                cos_to(&xs[j], xs[j + 1].p) * FRAC_1_PI,
                cos_to(&xs[j], xs[j - 1].p) * FRAC_1_PI,
            );
            weights.push((MERGE + j, w));
        }
    }
    weights
}

/// Walks from many pixels of `rel`; the prefixes of each walk that end on an emitter's front
/// are paths (in the furnace, every prefix), and for each the weights of its strategies are
/// summed, leaving out strategy `left_out` if given. Returns the number of paths, the longest,
/// whether a path through a specular vertex was seen, and the worst |Σw − 1|.
fn sums(
    rel: &str,
    walks: u32,
    length: usize,
    left_out: Option<usize>,
) -> (usize, usize, bool, f32) {
    sums_with(rel, walks, length, left_out, 0.0)
}

/// [`sums`] with merging within `radius` times the scene's bounding-sphere radius (0: BDPT),
/// for `vcm-full`; `left_out` MERGE leaves every merge out.
fn sums_with(
    rel: &str,
    walks: u32,
    length: usize,
    left_out: Option<usize>,
    radius: f32,
) -> (usize, usize, bool, f32) {
    sums_of(
        rel,
        walks,
        length,
        left_out,
        radius,
        Method::VcmFull,
        Method::VcmFull,
    )
}

/// The camera subpath's last vertex (its index among x0 … xk) in strategy `s` of a path of
/// `k` bounces: x(k−s) for a connection (s = 0: the emitter it hits), x_j for a merge there.
fn camera_end(s: usize, k: usize) -> usize {
    if s >= MERGE {
        s - MERGE
    } else {
        k - s
    }
}

/// [`sums_with`] for `method` (`vcm` or `vcm-full`), with the weights of `weights_of`: for
/// `vcm`, whose camera subpaths end at their first diffuse vertex x_d, the strategies are those
/// whose camera subpath ends at or before x_d (`camera_end` ≤ d: the connection and merge at
/// x_d, light tracing, emission met before any diffuse vertex).
fn sums_of(
    rel: &str,
    walks: u32,
    length: usize,
    left_out: Option<usize>,
    radius: f32,
    method: Method,
    weights_of: Method,
) -> (usize, usize, bool, f32) {
    let merge = MergeMis::new(
        radius * hexray::transport::merging::scene_radius(&load(rel).1),
        SIZE * SIZE,
        weights_of,
    );
    let (scene, flat) = load(rel);
    let camera = Camera::new(&scene.desc.camera, SIZE, SIZE);
    let n_c = camera_subpaths(
        &specular_pixels(&flat, &camera),
        specular_camera_subpaths(method, radius),
    );
    let (mut paths, mut longest, mut specular, mut worst) = (0, 0, false, 0.0f32);
    for index in 0..walks {
        let walk = walk(&flat, &camera, index, length);
        let n_c = n_c[(index % (SIZE * SIZE)) as usize] as f32;
        for end in 1..=walk.len() {
            let path = &walk[..end];
            if path[end - 1].emitter.is_none() {
                continue;
            }
            // x_d, the first diffuse vertex (x1 is path[0]); past the path's end if none.
            let first_diffuse = 1 + path.iter().position(|v| v.diffuse).unwrap_or(end);
            let total: f32 = strategy_weights(&flat, &camera, path, n_c, &merge)
                .iter()
                .filter(|(s, _)| method == Method::VcmFull || camera_end(*s, end) <= first_diffuse)
                .filter(|(s, _)| match left_out {
                    Some(MERGE) => *s < MERGE,
                    other => Some(*s) != other,
                })
                .map(|(_, w)| w)
                .sum();
            paths += 1;
            longest = longest.max(end);
            specular |= path.iter().any(|v| !v.diffuse && v.emitter.is_none());
            worst = worst.max((total - 1.0).abs());
        }
    }
    eprintln!(
        "{rel}: {paths} paths, longest {longest} bounces, specular vertices {specular}, worst |Σw − 1| {worst:.2e}"
    );
    (paths, longest, specular, worst)
}

#[test]
fn mis_weights_sum_to_one_on_tncg15_rooms_paths_through_its_mirrors() {
    let (paths, _, specular, worst) = sums("scenes/tncg15_room.json", 12000, 12, None);
    assert!(
        paths > 300 && specular,
        "too few paths, or none through a mirror"
    );
    assert!(worst < 1e-4, "worst |Σw − 1| = {worst:e}");
}

#[test]
fn mis_weights_sum_to_one_on_glass_rooms_paths_through_glass() {
    let (paths, _, specular, worst) = sums("scenes/glass_room.json", 12000, 12, None);
    assert!(
        paths > 300 && specular,
        "too few paths, or none through glass"
    );
    assert!(worst < 1e-4, "worst |Σw − 1| = {worst:e}");
}

#[test]
fn mis_weights_sum_to_one_on_cornell_boxs_paths() {
    let (paths, _, _, worst) = sums("scenes/cornell_box.json", 12000, 12, None);
    assert!(paths > 300, "too few paths");
    assert!(worst < 1e-4, "worst |Σw − 1| = {worst:e}");
}

/// In a white furnace every wall is an emitter that reflects, so every prefix of a walk is a
/// path: 60 bounces make paths far longer than any stored light subpath (20 vertices on
/// average at albedo 0.95).
#[test]
fn mis_weights_sum_to_one_on_paths_of_sixty_bounces() {
    let (paths, longest, _, worst) = sums("scenes/furnace/diffuse_0_95.json", 200, 60, None);
    assert!(paths >= 200 * 60 && longest == 60);
    assert!(worst < 1e-4, "worst |Σw − 1| = {worst:e}");
}

/// The check has power: with next-event estimation left out of the sum, the weights of the
/// remaining strategies no longer sum to 1.
#[test]
fn mis_weight_check_rejects_a_missing_strategy() {
    let (_, _, _, worst) = sums("scenes/cornell_box.json", 500, 12, Some(1));
    assert!(
        worst > 1e-2,
        "worst |Σw − 1| = {worst:e} with a strategy missing"
    );
}

/// VCM: with merges at a radius of 0.02 of the scene's bounding-sphere radius (0.22 in
/// tncg15_room, where the merges then carry up to 90 % of some paths' weight), every strategy's
/// weight, connections and merges, sums to 1.
#[test]
fn mis_weights_with_merging_sum_to_one_on_tncg15_rooms_paths() {
    let (paths, _, specular, worst) = sums_with("scenes/tncg15_room.json", 6000, 12, None, 0.02);
    assert!(paths > 150 && specular, "too few paths");
    assert!(worst < 1e-4, "worst |Σw − 1| = {worst:e}");
}

#[test]
fn mis_weights_with_merging_sum_to_one_on_glass_rooms_paths() {
    let (paths, _, specular, worst) = sums_with("scenes/glass_room.json", 6000, 12, None, 0.02);
    assert!(paths > 150 && specular, "too few paths");
    assert!(worst < 1e-4, "worst |Σw − 1| = {worst:e}");
}

#[test]
fn mis_weights_with_merging_sum_to_one_on_paths_of_sixty_bounces() {
    let (_, longest, _, worst) = sums_with("scenes/furnace/diffuse_0_95.json", 100, 60, None, 0.02);
    assert!(longest == 60);
    assert!(worst < 1e-4, "worst |Σw − 1| = {worst:e}");
}

/// With merging on, the connections' weights alone fall short of 1: the merges carry the rest.
#[test]
fn mis_weight_check_rejects_missing_merges() {
    let (_, _, _, worst) = sums_with("scenes/tncg15_room.json", 2000, 12, Some(MERGE), 0.02);
    assert!(
        worst > 1e-2,
        "worst |Σw − 1| = {worst:e} without the merges"
    );
}

/// [`sums_of`] for vcm, merging within 0.02 of the scene's bounding-sphere radius, with the
/// weights of `weights_of`.
fn first_diffuse_sums(
    rel: &str,
    walks: u32,
    length: usize,
    weights_of: Method,
) -> (usize, usize, bool, f32) {
    sums_of(rel, walks, length, None, 0.02, Method::Vcm, weights_of)
}

/// vcm, whose camera subpaths end at their first diffuse vertex: its weights sum to 1 over the
/// strategies it takes (the connection and the merge at that vertex, light tracing, emission
/// met through mirrors), on paths through the room's mirrors.
#[test]
fn first_diffuse_vcm_weights_sum_to_one_on_tncg15_rooms_paths() {
    let (paths, _, specular, worst) =
        first_diffuse_sums("scenes/tncg15_room.json", 6000, 12, Method::Vcm);
    assert!(paths > 150 && specular, "too few paths");
    assert!(worst < 1e-4, "worst |Σw − 1| = {worst:e}");
}

#[test]
fn first_diffuse_vcm_weights_sum_to_one_on_glass_rooms_paths() {
    let (paths, _, specular, worst) =
        first_diffuse_sums("scenes/glass_room.json", 6000, 12, Method::Vcm);
    assert!(paths > 150 && specular, "too few paths");
    assert!(worst < 1e-4, "worst |Σw − 1| = {worst:e}");
}

#[test]
fn first_diffuse_vcm_weights_sum_to_one_on_paths_of_sixty_bounces() {
    let (_, longest, _, worst) =
        first_diffuse_sums("scenes/furnace/diffuse_0_95.json", 100, 60, Method::Vcm);
    assert!(longest == 60);
    assert!(worst < 1e-4, "worst |Σw − 1| = {worst:e}");
}

/// The check has power: camera subpaths ended at their first diffuse vertex with vcm-full's
/// weights (which count the strategies of the camera subpaths that go on) fall short of 1.
#[test]
fn mis_weight_check_rejects_first_diffuse_ends_with_full_vcm_weights() {
    let (_, _, _, worst) = first_diffuse_sums("scenes/tncg15_room.json", 2000, 12, Method::VcmFull);
    assert!(
        worst > 1e-2,
        "worst |Σw − 1| = {worst:e} with vcm-full's weights"
    );
}
