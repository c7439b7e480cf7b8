//! Area lights: choosing an emitter (a triangle or a sphere) by power, a uniform point on it, and
//! the pdf of that choice with respect to solid angle at the receiving point.

use crate::layout::{FlatScene, NOT_AN_EMITTER, PRIM_SPHERE_BIT};
use crate::math::geometry::{
    offset_ray_origin, sphere_point_at, triangle_normal, triangle_point, Ray,
};
use crate::math::lanes::{self, F8, LANES, V8};
use crate::math::sampling::{
    orthonormal_basis, sample_cosine_hemisphere, sample_uniform_sphere, sample_uniform_triangle,
};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// A point on an emitter, chosen for next-event estimation.
#[derive(Clone, Copy, Debug, Default)]
pub struct LightSample {
    pub p: Vec3,
    pub p_err: Vec3,
    /// Unit normal of the emitting side: (v1 - v0) x (v2 - v0), or the sphere's normal.
    pub n: Vec3,
    /// Emitted radiance toward the front.
    pub le: Vec3,
    /// The probability density of this point with respect to area: pmf(triangle) / area.
    pub pdf_area: f32,
}

/// The row of the emitter table whose CDF interval holds `u`: the first row with cdf > u (the
/// last row if none before it), so row k is chosen with probability pmf_k. A binary search
/// whose steps depend only on the table's length: each halving keeps the upper half by a
/// select, not a branch, since which half holds `u` is a coin toss that a branch mispredicts
/// half the time (cachegrind: 8 % of a cornell_box render's mispredicts, docs/journal/2026-11-27_branches.md).
#[inline]
pub fn choose_emitter(scene: &FlatScene, u: f32) -> usize {
    first_above(scene.emitters.len(), |row| scene.emitters[row].cdf, u)
}

/// The first of rows 0..rows - 1 whose non-decreasing `cdf` exceeds `u`, or rows - 1.
#[inline]
fn first_above(rows: usize, cdf: impl Fn(usize) -> f32, u: f32) -> usize {
    let candidates = rows - 1;
    if candidates == 0 {
        return 0;
    }
    // Invariant: the answer lies in base..=base + size, and every row before base has
    // cdf <= u.
    let (mut base, mut size) = (0, candidates);
    while size > 1 {
        let half = size / 2;
        base = if cdf(base + half) <= u {
            base + half
        } else {
            base
        };
        size -= half;
    }
    base + usize::from(cdf(base) <= u)
}

/// Chooses an emitter in proportion to its power, then a point uniformly on its area: on a
/// triangle by the square-root warp, on a sphere by a uniform direction from its centre (the
/// point's error bound is `sphere_point`'s).
#[inline]
pub fn sample_emitter(scene: &FlatScene, u_select: f32, u1: f32, u2: f32) -> LightSample {
    let row = scene.emitters[choose_emitter(scene, u_select)];
    let pdf_area = row.pmf / row.area;
    if row.prim & PRIM_SPHERE_BIT != 0 {
        let sphere = &scene.spheres[(row.prim & !PRIM_SPHERE_BIT) as usize];
        let d = sample_uniform_sphere(u1, u2);
        let (p, p_err) = sphere_point_at(sphere, sphere.radius * d);
        return LightSample {
            p,
            p_err,
            n: sphere.normal(d),
            le: Vec3::from(scene.materials[sphere.material as usize].emission),
            pdf_area,
        };
    }
    let tri = &scene.triangles[row.prim as usize];
    let (_, b1, b2) = sample_uniform_triangle(u1, u2);
    let (p, p_err) = triangle_point(tri, b1, b2);
    LightSample {
        p,
        p_err,
        n: triangle_normal(tri),
        le: Vec3::from(scene.materials[tri.material as usize].emission),
        pdf_area,
    }
}

/// Points on emitters in lanes, as [`LightSample`] holds one.
#[derive(Clone, Copy, Debug)]
pub struct LightLanes {
    pub p: V8,
    pub p_err: V8,
    pub n: V8,
    pub le: V8,
    pub pdf_area: F8,
}

/// [`sample_emitter`] in the lanes `lanes` (bits), lane l with the numbers (`u_select`,
/// `u1`, `u2`) of its lane: the emitter chosen lane by lane, then the points on emitter
/// triangles in SIMD lanes (`sample_uniform_triangle` and `triangle_point`, operation for
/// operation), on spheres lane by lane. The other lanes hold no sample. The scene must have an
/// emitter, as a validated scene has.
#[inline]
pub fn sample_emitter_lanes(
    scene: &FlatScene,
    u_select: F8,
    u1: F8,
    u2: F8,
    lanes: u32,
) -> LightLanes {
    let (us, uo1, uo2) = (u_select.as_array(), u1.as_array(), u2.as_array());
    let mut rows = [scene.emitters[0]; LANES];
    let mut spheres = 0u32;
    for l in 0..LANES {
        if lanes & (1 << l) != 0 {
            rows[l] = scene.emitters[choose_emitter(scene, us[l])];
            spheres |= u32::from(rows[l].prim & PRIM_SPHERE_BIT != 0) << l;
        }
    }
    // A triangle for every lane (a lane without one repeats an emitter triangle, or the
    // first triangle), whose results the sphere lanes replace below.
    let fallback = scene
        .emitters
        .iter()
        .find(|e| e.prim & PRIM_SPHERE_BIT == 0)
        .map_or(0, |e| e.prim);
    let index = lanes::uints(|l| {
        if rows[l].prim & PRIM_SPHERE_BIT == 0 {
            rows[l].prim
        } else {
            fallback
        }
    });
    let mut out = LightLanes {
        p: V8::default(),
        p_err: V8::default(),
        n: V8::default(),
        le: V8::default(),
        pdf_area: lanes::floats(|l| rows[l].pmf) / lanes::floats(|l| rows[l].area),
    };
    if !scene.triangles.is_empty() {
        let corner = |offset| V8::gather_from(&scene.triangles, index, offset);
        // `sample_uniform_triangle`: sqrt(u1) (1 - u2) and sqrt(u1) u2
        let su = u1.sqrt();
        let (b1, b2) = (su * (F8::splat(1.0) - u2), su * u2);
        (out.p, out.p_err) = lanes::triangle_point(&corner(0), &corner(4), &corner(8), b1, b2);
        out.n = corner(12);
        let material = lanes::uints(|l| scene.triangles[index.as_array()[l] as usize].material);
        out.le = V8::gather_from(&scene.materials, material, 4);
    }
    let mut sphere_lanes = spheres & lanes;
    while sphere_lanes != 0 {
        let l = sphere_lanes.trailing_zeros() as usize;
        sphere_lanes &= sphere_lanes - 1;
        let s = sample_emitter(scene, us[l], uo1[l], uo2[l]);
        out.p.set_lane(l, s.p);
        out.p_err.set_lane(l, s.p_err);
        out.n.set_lane(l, s.n);
        out.le.set_lane(l, s.le);
        out.pdf_area.as_mut_array()[l] = s.pdf_area;
    }
    out
}

/// Where a light subpath starts (light tracing, BDPT): a point on an emitter and a direction
/// from its front.
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    pub point: LightSample,
    /// Unit direction of emission, cosine-distributed about the emitter's normal.
    pub dir: Vec3,
    /// cos θ between the normal and `dir` (> 0).
    pub cos: f32,
    /// Solid-angle density of `dir`: cos θ / π.
    pub pdf_dir: f32,
}

/// Starts a light subpath: an emitter point chosen as [`sample_emitter`] chooses it (so the two
/// strategies that sample a light point, next-event estimation and light subpaths, share one
/// area density), then a direction from its front with density cos θ / π, which makes the first
/// throughput Le cos θ / (p_A · cos θ / π) = π Le / p_A, the same for every direction.
#[inline]
pub fn sample_emission(scene: &FlatScene, u_point: [f32; 4], u_dir: [f32; 4]) -> EmissionSample {
    let point = sample_emitter(scene, u_point[0], u_point[1], u_point[2]);
    let local = sample_cosine_hemisphere(u_dir[0], u_dir[1]);
    let (t, b) = orthonormal_basis(point.n);
    EmissionSample {
        point,
        dir: local.x * t + local.y * b + local.z * point.n,
        cos: local.z,
        pdf_dir: local.z * FRAC_1_PI,
    }
}

/// The area density with which [`sample_emitter`] picks points on primitive `prim` (a `prims`
/// reference, as `SurfaceHit::prim`; 0 for a primitive that is not in the emitter table).
#[inline]
pub fn emitter_pdf_area(scene: &FlatScene, prim: u32) -> f32 {
    let row = if prim & PRIM_SPHERE_BIT != 0 {
        scene.spheres[(prim & !PRIM_SPHERE_BIT) as usize].emitter
    } else {
        scene.triangles[prim as usize].emitter
    };
    if row == NOT_AN_EMITTER {
        return 0.0;
    }
    let e = &scene.emitters[row as usize];
    e.pmf / e.area
}

/// Converts an area density at a light point to a solid-angle density at the receiver:
/// p_ω = p_A · r² / |cos θ_l| (the Jacobian dA = r² dω / |cos θ_l|).
#[inline]
pub fn area_to_solid_angle(pdf_area: f32, dist2: f32, cos_light: f32) -> f32 {
    pdf_area * dist2 / cos_light.abs()
}

#[cfg(test)]
mod tests {
    use super::first_above;

    /// The definition: the first of rows 0..rows - 1 with cdf > u, else the last row.
    fn first_above_by_scan(cdf: &[f32], u: f32) -> usize {
        (0..cdf.len() - 1)
            .find(|&row| cdf[row] > u)
            .unwrap_or(cdf.len() - 1)
    }

    #[test]
    fn the_emitter_search_picks_the_first_row_whose_cdf_exceeds_u() {
        // Tables of 1 to 40 rows with runs of equal entries (emitters of zero power), and u at
        // every entry, just beside it, 0 and just below 1.
        let mut state = 12345u32;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            state >> 8
        };
        for rows in 1..=40 {
            for _ in 0..20 {
                let mut sum = 0.0f32;
                let mut cdf: Vec<f32> = (0..rows)
                    .map(|_| {
                        if next() % 4 != 0 {
                            sum += (next() % 100) as f32;
                        }
                        sum
                    })
                    .collect();
                let total = cdf[rows - 1].max(1.0);
                cdf.iter_mut().for_each(|c| *c /= total);
                let mut us = vec![0.0, 1.0 - f32::EPSILON / 2.0];
                for &c in &cdf {
                    us.extend([c, c.next_down(), c.next_up()]);
                }
                for u in us {
                    assert_eq!(
                        first_above(rows, |row| cdf[row], u),
                        first_above_by_scan(&cdf, u),
                        "rows {rows}, u {u}, cdf {cdf:?}"
                    );
                }
            }
        }
    }

    /// A room lit by two emitter triangles of different radiance and two emitter spheres:
    /// every lane of `sample_emitter_lanes` is `sample_emitter` with that lane's numbers, bit
    /// for bit, whichever lanes are asked for, and triangles and spheres are both chosen.
    #[test]
    fn emitter_points_in_lanes_are_sample_emitters_points() {
        use super::{sample_emitter, sample_emitter_lanes};
        use crate::layout::{FlatScene, PRIM_SPHERE_BIT};
        use crate::math::lanes::{floats, LANES};
        use crate::scene::Scene;
        let json = r#"{
            "name": "mixed_lights",
            "camera": {"eye": [0, 0, -5], "look_at": [0, 0, 0], "up": [0, 1, 0], "vfov_deg": 40},
            "materials": {
                "wall": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
                "lamp": {"type": "emitter", "radiance": [4, 3, 2]},
                "bulb": {"type": "emitter", "radiance": [1, 1, 8], "albedo": [0.2, 0.2, 0.2]}
            },
            "triangles": [
                {"v": [[-2, -1, 0], [2, -1, 0], [2, -1, 4]], "material": "wall"},
                {"v": [[-1, 2, 1], [1, 2, 1], [1, 2, 3]], "material": "lamp"},
                {"v": [[-1, 2, 1], [1, 2, 3], [-1, 2, 3]], "material": "bulb"}
            ],
            "spheres": [
                {"center": [1.5, 0, 2], "radius": 0.25, "material": "bulb"},
                {"center": [-1.5, 0.5, 2], "radius": 0.5, "material": "lamp"}
            ]
        }"#;
        let scene = Scene::from_json(json, std::path::Path::new("mixed_lights.json")).unwrap();
        let flat = FlatScene::build(&scene, crate::accel::bvh::Traversal::Cpu);
        let mut chosen = [0u32; 2];
        for i in 0..400u32 {
            let u = |k: u32, l: usize| {
                crate::math::sampling::u32_to_unit_f32(
                    crate::math::sampling::pcg4d([i, l as u32, k, 9])[0],
                )
            };
            let (us, u1, u2) = (
                floats(|l| u(0, l)),
                floats(|l| u(1, l)),
                floats(|l| u(2, l)),
            );
            let lanes = if i % 3 == 0 { 0xff } else { (i * 37) & 0xff };
            let got = sample_emitter_lanes(&flat, us, u1, u2, lanes);
            for l in (0..LANES).filter(|l| lanes & (1 << l) != 0) {
                let want = sample_emitter(&flat, u(0, l), u(1, l), u(2, l));
                let bits = |v: glam::Vec3| v.to_array().map(f32::to_bits);
                let lane = |v: &crate::math::lanes::V8| bits(v.lane(l));
                assert_eq!(lane(&got.p), bits(want.p), "{i}, lane {l}");
                assert_eq!(lane(&got.p_err), bits(want.p_err), "{i}, lane {l}");
                assert_eq!(lane(&got.n), bits(want.n), "{i}, lane {l}");
                assert_eq!(lane(&got.le), bits(want.le), "{i}, lane {l}");
                assert_eq!(
                    got.pdf_area.as_array()[l].to_bits(),
                    want.pdf_area.to_bits()
                );
                let row = flat.emitters[super::choose_emitter(&flat, u(0, l))];
                chosen[usize::from(row.prim & PRIM_SPHERE_BIT != 0)] += 1;
            }
        }
        assert!(chosen[0] > 100 && chosen[1] > 100, "{chosen:?}");
    }
}

/// Next-event estimation's link from a surface point to a point on the emitters: the shadow ray
/// to trace, what the point emits, the cosine at the surface and the point's pdf in solid angle.
#[derive(Clone, Copy, Debug)]
pub struct EmitterLink {
    pub shadow: Ray,
    pub le: Vec3,
    pub cos_s: f32,
    pub light_pdf: f32,
}

/// Links the point `p` (error bound `p_err`, geometric normal `n`, `n_facing` on the side that
/// is shaded) to the emitter point `ls`: None where either side faces away. The shadow ray runs
/// between the two points offset off their surfaces, with t in (0, 1).
#[inline]
pub fn link_to_emitter(
    p: Vec3,
    p_err: Vec3,
    n: Vec3,
    n_facing: Vec3,
    ls: &LightSample,
) -> Option<EmitterLink> {
    let to_light = ls.p - p;
    let dist2 = to_light.length_squared();
    let wi = to_light / dist2.sqrt();
    let cos_s = n_facing.dot(wi);
    let cos_l = -ls.n.dot(wi);
    if !(cos_s > 0.0 && cos_l > 0.0 && dist2 > 0.0) {
        return None;
    }
    let origin = offset_ray_origin(p, p_err, n, wi);
    let light_point = offset_ray_origin(ls.p, ls.p_err, ls.n, -wi);
    Some(EmitterLink {
        shadow: Ray {
            o: origin,
            d: light_point - origin,
        },
        le: ls.le,
        cos_s,
        light_pdf: area_to_solid_angle(ls.pdf_area, dist2, cos_l),
    })
}
