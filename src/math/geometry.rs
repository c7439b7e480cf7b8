//! Ray–primitive intersection with floating-point error bounds, and spawning rays that cannot
//! hit the surface they leave.
//!
//! The approach is pbrt-v4's (Pharr, Jakob, Humphreys, *Physically Based Rendering*, 4th ed.,
//! section 6.8): every hit point carries a conservative bound `p_err` on the rounding error of
//! its coordinates; a spawned ray starts at the hit point pushed along the geometric normal just
//! past that bound (to the side the ray leaves on), so the true surface is behind it; and an
//! intersection is only accepted when its parameter `t` exceeds the rounding error of the test
//! that computed it. No fixed epsilon, and nothing proportional to the scene's size: the offset
//! scales with the magnitude of the coordinates, which is what far-from-origin scenes need.

use crate::layout::{Sphere, Triangle, TrianglePack};
use glam::{Vec3, Vec3A, Vec4};

/// Half an ulp of 1.0 in f32: the relative rounding error of one operation.
pub const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// The bound gamma_n = n eps / (1 - n eps) on the accumulated relative error of n operations
/// (Higham; pbrt-v4 eq. 6.22).
#[inline]
pub const fn gamma(n: i32) -> f32 {
    (n as f32 * MACHINE_EPSILON) / (1.0 - n as f32 * MACHINE_EPSILON)
}

/// A ray `o + t d`; `d` need not be unit length (shadow rays span [0, 1] over a segment).
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
}

/// The next f32 above `v` (pbrt's `NextFloatUp`), through the bits, exactly as WGSL does it.
#[inline]
pub fn next_float_up(v: f32) -> f32 {
    if v == f32::INFINITY {
        return v;
    }
    // -0 and +0 both step to the smallest positive subnormal.
    let bits = if v == 0.0 { 0 } else { v.to_bits() };
    f32::from_bits(if v >= 0.0 {
        bits.wrapping_add(1)
    } else {
        bits.wrapping_sub(1)
    })
}

/// The next f32 below `v` (pbrt's `NextFloatDown`).
#[inline]
pub fn next_float_down(v: f32) -> f32 {
    if v == f32::NEG_INFINITY {
        return v;
    }
    // +0 and -0 both step to the smallest negative subnormal.
    let bits = if v == 0.0 { 0x8000_0000 } else { v.to_bits() };
    f32::from_bits(if v > 0.0 {
        bits.wrapping_sub(1)
    } else {
        bits.wrapping_add(1)
    })
}

/// A point that is certainly on the side of the surface that direction `w` leaves to:
/// `p` moved along the unit geometric normal `n` by the projection of its error box onto `n`,
/// then rounded away from the surface (pbrt-v4's `OffsetRayOrigin`, eq. 6.28).
#[inline]
pub fn offset_ray_origin(p: Vec3, p_err: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(p_err);
    let mut offset = d * n;
    if w.dot(n) < 0.0 {
        offset = -offset;
    }
    step_away(p + offset, offset)
}

/// Each coordinate of `po` stepped one ulp the way its `offset` points ([`next_float_up`] where
/// it is positive, [`next_float_down`] where negative, unchanged where 0 or NaN), one coordinate
/// after another.
#[inline]
pub fn step_away_scalar(mut po: Vec3, offset: Vec3) -> Vec3 {
    for i in 0..3 {
        if offset[i] > 0.0 {
            po[i] = next_float_up(po[i]);
        } else if offset[i] < 0.0 {
            po[i] = next_float_down(po[i]);
        }
    }
    po
}

/// [`step_away_scalar`] with the three coordinates in SSE2 lanes and masks for its branches,
/// bit for bit the same (`step_away_matches_the_scalar_steps`): the offset's signs vary from
/// ray to ray, and the branches cost the path tracer more than the arithmetic.
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn step_away(po: Vec3, offset: Vec3) -> Vec3 {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of x86_64.
    unsafe {
        let x = _mm_set_ps(0.0, po.z, po.y, po.x);
        let s = _mm_set_ps(0.0, offset.z, offset.y, offset.x);
        let zero = _mm_setzero_ps();
        let int = _mm_castps_si128;
        let (and, or, andnot) = (_mm_and_si128, _mm_or_si128, _mm_andnot_si128);
        let up = int(_mm_cmpgt_ps(s, zero));
        let down = int(_mm_cmplt_ps(s, zero));
        let bits = int(x);
        // ±0 steps from the bits of +0 (up) or -0 (down), as next_float_up/down take them.
        let is_zero = int(_mm_cmpeq_ps(x, zero));
        let zero_bits = and(down, _mm_set1_epi32(i32::MIN));
        let base = or(and(is_zero, zero_bits), andnot(is_zero, bits));
        // Up: +1 where x >= 0 (false for NaN), else -1; down: -1 where x > 0, else +1.
        let (one, minus_one) = (_mm_set1_epi32(1), _mm_set1_epi32(-1));
        let ge = int(_mm_cmpge_ps(x, zero));
        let gt = int(_mm_cmpgt_ps(x, zero));
        let delta_up = or(and(ge, one), andnot(ge, minus_one));
        let delta_down = or(and(gt, minus_one), andnot(gt, one));
        let delta = or(and(up, delta_up), andnot(up, delta_down));
        let stepped = _mm_add_epi32(base, delta);
        // Unchanged: offset 0 or NaN, or the infinity the step points to.
        let at_inf = or(
            and(up, int(_mm_cmpeq_ps(x, _mm_set1_ps(f32::INFINITY)))),
            and(down, int(_mm_cmpeq_ps(x, _mm_set1_ps(f32::NEG_INFINITY)))),
        );
        let moves = andnot(at_inf, or(up, down));
        let out = _mm_castsi128_ps(or(and(moves, stepped), andnot(moves, bits)));
        let mut lanes = [0.0f32; 4];
        _mm_storeu_ps(lanes.as_mut_ptr(), out);
        Vec3::new(lanes[0], lanes[1], lanes[2])
    }
}

/// [`step_away_scalar`] where there is no SSE2.
#[cfg(not(target_arch = "x86_64"))]
#[inline]
pub fn step_away(po: Vec3, offset: Vec3) -> Vec3 {
    step_away_scalar(po, offset)
}

/// `|a| x |b|` term by term: a bound on the magnitude of the products summed in `a x b`.
#[inline]
fn abs_cross(a: Vec3, b: Vec3) -> Vec3 {
    let (a, b) = (a.abs(), b.abs());
    Vec3::new(
        a.y * b.z + a.z * b.y,
        a.z * b.x + a.x * b.z,
        a.x * b.y + a.y * b.x,
    )
}

/// A candidate intersection: the ray parameter, a bound on its rounding error, and the
/// barycentrics of the hit (b1, b2; triangles only).
#[derive(Clone, Copy, Debug)]
pub struct TriangleHit {
    pub t: f32,
    pub t_err: f32,
    pub b1: f32,
    pub b2: f32,
}

/// Möller–Trumbore ("Fast, Minimum Storage Ray/Triangle Intersection", 1997), with the
/// parameter accepted only where it exceeds its own error bound.
///
/// The triple product `t · det = e2 · (s × e1)` is computed from differences of exact inputs (so
/// each of `s`, `e1`, `e2` has relative error eps) and three more rounded operations; its absolute
/// error is below gamma(7) times the same sum taken over magnitudes. A ray spawned by
/// [`offset_ray_origin`] starts on the far side of the true surface, so its true `t` for that
/// surface is <= 0, and any computed `t` above the bound is genuine.
#[inline]
pub fn intersect_triangle(ray: &Ray, tri: &Triangle) -> Option<TriangleHit> {
    let v0 = Vec3::from(tri.v0);
    let e1 = Vec3::from(tri.v1) - v0;
    let e2 = Vec3::from(tri.v2) - v0;
    let pvec = ray.d.cross(e2);
    let det = e1.dot(pvec);
    if det == 0.0 {
        return None;
    }
    // The barycentrics times |det| (the sign of det folded in) are compared with |det|, so a
    // miss costs no division.
    let sign = 1.0f32.copysign(det);
    let abs_det = det.abs();
    let s = ray.o - v0;
    let u = s.dot(pvec) * sign;
    if !(0.0..=abs_det).contains(&u) {
        return None;
    }
    let qvec = s.cross(e1);
    let v = ray.d.dot(qvec) * sign;
    if v < 0.0 || u + v > abs_det {
        return None;
    }
    let inv_det = 1.0 / abs_det;
    let t = e2.dot(qvec) * sign * inv_det;
    let t_err = gamma(7) * e2.abs().dot(abs_cross(s, e1)) * inv_det;
    // Written so that a NaN t (degenerate input) is rejected too.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(t > t_err) {
        return None;
    }
    Some(TriangleHit {
        t,
        t_err,
        b1: u * inv_det,
        b2: v * inv_det,
    })
}

/// A ray's origin and direction, each coordinate splatted over four lanes.
#[derive(Clone, Copy, Debug)]
pub struct Ray4 {
    pub o: [Vec4; 3],
    pub d: [Vec4; 3],
}

impl Ray4 {
    #[inline]
    pub fn new(ray: &Ray) -> Ray4 {
        Ray4 {
            o: ray.o.to_array().map(Vec4::splat),
            d: ray.d.to_array().map(Vec4::splat),
        }
    }
}

/// What [`intersect_triangles4`] found: bit `lane` of `mask` set where that lane's triangle is
/// hit, and per lane what [`TriangleHit`] holds.
#[derive(Clone, Copy, Debug)]
pub struct TriangleHits4 {
    pub mask: u32,
    pub t: [f32; 4],
    pub t_err: [f32; 4],
    pub b1: [f32; 4],
    pub b2: [f32; 4],
}

impl TriangleHits4 {
    /// No lane hit.
    pub const MISS: TriangleHits4 = TriangleHits4 {
        mask: 0,
        t: [0.0; 4],
        t_err: [0.0; 4],
        b1: [0.0; 4],
        b2: [0.0; 4],
    };
}

/// [`intersect_triangle`] on four triangles at once, one per lane. Every lane performs the
/// scalar test's operations in the scalar test's order (the cross and dot products expanded as
/// glam writes them, no fused multiply-adds), so a lane's hit, `t`, error bound and barycentrics
/// are bit for bit the scalar test's: the early exits become lane masks and nothing else
/// changes. A miss costs the whole test, but four triangles cost one test and no mispredicted
/// branches.
#[inline]
pub fn intersect_triangles4(ray: &Ray4, pack: &TrianglePack) -> TriangleHits4 {
    let [ox, oy, oz] = ray.o;
    let [dx, dy, dz] = ray.d;
    let [v0x, v0y, v0z] = pack.v0;
    let [e1x, e1y, e1z] = pack.e1;
    let [e2x, e2y, e2z] = pack.e2;
    // pvec = d x e2, det = e1 . pvec
    let px = dy * e2z - e2y * dz;
    let py = dz * e2x - e2z * dx;
    let pz = dx * e2y - e2x * dy;
    let det = e1x * px + e1y * py + e1z * pz;
    let sign = Vec4::ONE.copysign(det);
    let abs_det = det.abs();
    // s = o - v0, u = (s . pvec) sign
    let (sx, sy, sz) = (ox - v0x, oy - v0y, oz - v0z);
    let u = (sx * px + sy * py + sz * pz) * sign;
    // qvec = s x e1, v = (d . qvec) sign
    let qx = sy * e1z - e1y * sz;
    let qy = sz * e1x - e1z * sx;
    let qz = sx * e1y - e1x * sy;
    let v = (dx * qx + dy * qy + dz * qz) * sign;
    let inv_det = Vec4::ONE / abs_det;
    let t = (e2x * qx + e2y * qy + e2z * qz) * sign * inv_det;
    // t_err = gamma(7) (|e2| . (|s| x |e1|)) / |det|
    let (ax, ay, az) = (sx.abs(), sy.abs(), sz.abs());
    let (bx, by, bz) = (e1x.abs(), e1y.abs(), e1z.abs());
    let (cx, cy, cz) = (ay * bz + az * by, az * bx + ax * bz, ax * by + ay * bx);
    let t_err =
        Vec4::splat(gamma(7)) * (e2x.abs() * cx + e2y.abs() * cy + e2z.abs() * cz) * inv_det;
    // The scalar test's exits, in its order, as masks (each written so a NaN fails as there).
    let hit = det.cmpne(Vec4::ZERO)
        & u.cmpge(Vec4::ZERO)
        & u.cmple(abs_det)
        & !v.cmplt(Vec4::ZERO)
        & !(u + v).cmpgt(abs_det)
        & t.cmpgt(t_err);
    TriangleHits4 {
        mask: hit.bitmask(),
        t: t.to_array(),
        t_err: t_err.to_array(),
        b1: (u * inv_det).to_array(),
        b2: (v * inv_det).to_array(),
    }
}

/// A candidate sphere intersection: the nearest root above its error bound.
#[derive(Clone, Copy, Debug)]
pub struct SphereHit {
    pub t: f32,
    pub t_err: f32,
}

/// Ray–sphere in the numerically careful form of Haines et al., "Precision Improvements for
/// Ray/Sphere Intersection" (Ray Tracing Gems, ch. 7): the discriminant from the distance of the
/// centre to the ray (no cancellation of two large squares), and the two roots as `q / a` and
/// `c / q` (no cancellation of -b and the square root).
///
/// The root `c / q` near a surface the ray starts on carries the absolute error of
/// `c = |f|^2 - r^2`, about eps (|f|^2 + r^2), divided by |q|; a root is accepted only above
/// that bound (with slack for the remaining operations).
#[inline]
pub fn intersect_sphere(ray: &Ray, sphere: &Sphere) -> Option<SphereHit> {
    let center = Vec3::from(sphere.center);
    let r = sphere.radius;
    let f = ray.o - center;
    let a = ray.d.dot(ray.d);
    let b_half = -f.dot(ray.d);
    let l = f + (b_half / a) * ray.d;
    let disc = a * (r * r - l.dot(l));
    if disc < 0.0 {
        return None;
    }
    let c = f.dot(f) - r * r;
    let q = b_half + b_half.signum() * disc.sqrt();
    if q == 0.0 {
        return None;
    }
    let (ta, tb) = (c / q, q / a);
    let (t0, t1) = if ta <= tb { (ta, tb) } else { (tb, ta) };
    let c_err = (f.dot(f) + r * r) / q.abs();
    let err0 = gamma(8) * (t0.abs() + c_err);
    if t0 > err0 {
        return Some(SphereHit { t: t0, t_err: err0 });
    }
    let err1 = gamma(8) * (t1.abs() + c_err);
    if t1 > err1 {
        return Some(SphereHit { t: t1, t_err: err1 });
    }
    None
}

/// What the integrator needs of the closest hit: where, how uncertain, which way the surface
/// faces, and what it is made of.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub t: f32,
    /// Hit point, recomputed from the surface's own description (not `o + t d`).
    pub p: Vec3,
    /// Conservative bound on the absolute error of each coordinate of `p`.
    pub p_err: Vec3,
    /// Unit geometric normal: (v1 - v0) x (v2 - v0) for triangles, outward for spheres
    /// (inward for a flipped one).
    pub n: Vec3,
    pub material: u32,
    /// The `prims` entry that was hit (triangle index, or sphere index with the sphere bit).
    pub prim: u32,
}

/// The point of a triangle at barycentrics (1 - b1 - b2, b1, b2).
#[inline]
pub fn triangle_point(tri: &Triangle, b1: f32, b2: f32) -> (Vec3, Vec3) {
    triangle_point_at(tri, Vec3::new(1.0 - b1 - b2, b1, b2))
}

/// The point of a triangle at barycentrics b = (b0, b1, b2), with pbrt-v4's bound
/// gamma(7) (|b0 p0| + |b1 p1| + |b2 p2|) on its error (eq. 6.34).
#[inline]
fn triangle_point_at(tri: &Triangle, b: Vec3) -> (Vec3, Vec3) {
    let (p0, p1, p2) = (Vec3::from(tri.v0), Vec3::from(tri.v1), Vec3::from(tri.v2));
    let p = b.x * p0 + b.y * p1 + b.z * p2;
    let p_err = gamma(7) * ((b.x * p0).abs() + (b.y * p1).abs() + (b.z * p2).abs());
    (p, p_err)
}

/// The point of a triangle hit at barycentrics (b1, b2), moved into the triangle where it lies
/// closer to an edge than its own error bound, for spawning rays from it.
///
/// [`offset_ray_origin`] moves a point off its triangle's plane along the normal, which takes it
/// past the error box across that plane but not across the planes of the neighbouring faces: a
/// hit on the edge where two faces of a closed box meet at 90 degrees is computed on, or one ulp
/// beyond, the other face's plane, and a ray spawned there can leave through that face
/// (`tests/stability_thin.rs`). So each barycentric b_i is raised to at least
/// m |e_i| / (2 A), which puts the point at distance >= m from edge e_i (opposite vertex i; 2A
/// = |e1 x e2|), m twice the L1 norm of the error box, and the three renormalised. Points
/// farther inside than that (all but a sliver of width ~1e-6 relative along the edges) are
/// returned as [`triangle_point`] computes them; the others move by about m, within the
/// triangle. A triangle too small for such a margin gets the point nearest its centroid the
/// clamp gives, still on the triangle.
#[inline]
pub fn triangle_hit_point(tri: &Triangle, b1: f32, b2: f32) -> (Vec3, Vec3) {
    let (p, p_err) = triangle_point(tri, b1, b2);
    let b = Vec3::new(1.0 - b1 - b2, b1, b2);
    let (p0, p1, p2) = (Vec3::from(tri.v0), Vec3::from(tri.v1), Vec3::from(tri.v2));
    let two_area = (p1 - p0).cross(p2 - p0).dot(Vec3::from(tri.n));
    let margin = 2.0 * (p_err.x + p_err.y + p_err.z);
    let edges = Vec3::new((p2 - p1).length(), (p2 - p0).length(), (p1 - p0).length());
    let least = edges * (margin / two_area);
    // A degenerate (or NaN) area leaves the point as it is.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if b.cmpge(least).all() || !(two_area > 0.0) {
        return (p, p_err);
    }
    let raised = b.max(least);
    triangle_point_at(tri, raised / (raised.x + raised.y + raised.z))
}

/// Unit geometric normal of a triangle, (v1 - v0) x (v2 - v0) normalised (stored with it).
#[inline]
pub fn triangle_normal(tri: &Triangle) -> Vec3 {
    Vec3::from(tri.n)
}

/// The point of a sphere hit at `t`, projected back onto the sphere (which removes the error of
/// `o + t d` along the normal); the bound is pbrt-v4's gamma(5)|p| for the reprojection, plus the
/// rounding of adding the centre back.
#[inline]
pub fn sphere_point(ray: &Ray, sphere: &Sphere, t: f32) -> (Vec3, Vec3, Vec3) {
    let local = ray.o - Vec3::from(sphere.center) + t * ray.d;
    let local = local * (sphere.radius / local.length());
    let (p, p_err) = sphere_point_at(sphere, local);
    (p, p_err, sphere.normal(local / sphere.radius))
}

/// The point at offset `local` (of length r, up to rounding) from a sphere's centre, and its
/// error bound: gamma(5)|local| for the offset's rounding, plus the rounding of adding the
/// centre. Shared by hits (`sphere_point`) and sampled emitter points (`light::sample_emitter`).
#[inline]
pub fn sphere_point_at(sphere: &Sphere, local: Vec3) -> (Vec3, Vec3) {
    let p = Vec3::from(sphere.center) + local;
    (p, gamma(5) * local.abs() + gamma(2) * p.abs())
}

/// The slab test (Kay and Kajiya) against four boxes at once, given as rows of their bounds
/// (`min[axis]` holds the four boxes' minima on that axis), with pbrt-v4's 1 + 2 gamma(3)
/// widening of the far distance so that rounding never culls a box the ray touches. Returns, per
/// box, the distance at which the ray enters it (0 when it starts inside), and a mask with bit
/// c set where the ray enters box c no later than `t_max`. The CPU's wide nodes are rows of four
/// such boxes (`wide_bvh::intersect_wide`); the shader's `intersect_aabb4` is the same test on
/// a four-wide node (it returns -1 for the misses and builds the mask from the distances; here
/// SSE's movemask gives it in one instruction).
#[inline]
pub fn intersect_boxes4(
    min: [Vec4; 3],
    max: [Vec4; 3],
    o: Vec3,
    inv_d: Vec3,
    t_max: f32,
) -> (Vec4, u32) {
    let slab = |lo: Vec4, hi: Vec4, o: f32, inv_d: f32| {
        let t_lo = (lo - Vec4::splat(o)) * inv_d;
        let t_hi = (hi - Vec4::splat(o)) * inv_d;
        (t_lo.min(t_hi), t_lo.max(t_hi))
    };
    let (near_x, far_x) = slab(min[0], max[0], o.x, inv_d.x);
    let (near_y, far_y) = slab(min[1], max[1], o.y, inv_d.y);
    let (near_z, far_z) = slab(min[2], max[2], o.z, inv_d.z);
    let t_near = near_x.max(near_y).max(near_z).max(Vec4::ZERO);
    let t_far = far_x.min(far_y).min(far_z) * (1.0 + 2.0 * gamma(3));
    let entered = t_near.cmple(t_far.min(Vec4::splat(t_max))).bitmask();
    (t_near, entered)
}

/// 1/d per component, with zero components nudged to 1e-30 (keeping the sign) so that the slab
/// test never computes 0 x inf.
#[inline]
pub fn safe_inverse(d: Vec3) -> Vec3 {
    let d = Vec3A::from(d);
    let tiny = d.abs().cmplt(Vec3A::splat(1e-30));
    let nudged = Vec3A::select(tiny, Vec3A::splat(1e-30).copysign(d), d);
    Vec3::from(Vec3A::ONE / nudged)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The SSE2 step is the scalar one bit for bit, on zeros of both signs, subnormals, the
    /// largest finite values, infinities and NaN, with offsets of every sign, 0 and NaN.
    #[test]
    fn step_away_matches_the_scalar_steps() {
        let values = [
            0.0,
            -0.0,
            f32::from_bits(1),
            -f32::from_bits(1),
            1.0,
            -1.0,
            3.5e-20,
            -7.25e12,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let offsets = [
            1e-6,
            -1e-6,
            0.0,
            -0.0,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        for &a in &values {
            for &b in &values {
                for &oa in &offsets {
                    for &ob in &offsets {
                        let (po, off) = (Vec3::new(a, b, a), Vec3::new(oa, ob, -oa));
                        let (want, got) = (step_away_scalar(po, off), step_away(po, off));
                        for i in 0..3 {
                            assert_eq!(got[i].to_bits(), want[i].to_bits(), "{po} {off} lane {i}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn next_float_steps_one_ulp() {
        for v in [0.0f32, -0.0, 1.0, -1.0, 1e-40, 3.0e38, -7.5] {
            assert!(next_float_up(v) > v);
            assert!(next_float_down(v) < v);
        }
        assert_eq!(next_float_up(1.0), 1.0 + f32::EPSILON);
    }

    #[test]
    fn triangle_hit_in_the_middle() {
        let tri = Triangle {
            v0: [0.0, 0.0, 0.0],
            v1: [1.0, 0.0, 0.0],
            v2: [0.0, 1.0, 0.0],
            ..Default::default()
        };
        let ray = Ray {
            o: Vec3::new(0.25, 0.25, 1.0),
            d: Vec3::new(0.0, 0.0, -1.0),
        };
        let h = intersect_triangle(&ray, &tri).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6);
        assert!((h.b1 - 0.25).abs() < 1e-6 && (h.b2 - 0.25).abs() < 1e-6);
    }

    /// The four-lane test is the scalar test in each lane, bit for bit: hit or miss, t, its
    /// error bound and the barycentrics, over random triangles and rays, rays along the axes
    /// (zero direction components), rays leaving a triangle's own surface (where the error
    /// bound decides) and degenerate triangles (det = 0).
    #[test]
    fn four_lane_triangle_test_is_the_scalar_test_in_each_lane() {
        let rnd = |i: u32, k: u32| {
            crate::math::sampling::u32_to_unit_f32(crate::math::sampling::pcg4d([i, k, 11, 12])[0])
                * 2.0
                - 1.0
        };
        let v = |i: u32, k: u32| [rnd(i, k), rnd(i, k + 1), rnd(i, k + 2)];
        let (mut hits, mut misses) = (0, 0);
        for i in 0..20_000u32 {
            let mut tris: [Triangle; 4] = std::array::from_fn(|l| {
                let l = l as u32 * 9;
                Triangle::new(v(i, l), v(i, l + 3), v(i, l + 6), 0)
            });
            // Every eighth pack has a degenerate triangle (all three vertices on a line).
            if i % 8 == 0 {
                let (a, b) = (Vec3::from(tris[1].v0), Vec3::from(tris[1].v1));
                tris[1].v2 = (a + 0.5 * (b - a)).into();
            }
            let mut pack = TrianglePack::default();
            for (l, t) in tris.iter().enumerate() {
                pack.set_triangle(l, t);
            }
            // Most rays aim at a point of one lane's triangle (barycentrics up to 0.6 each, so
            // some outside it); every fourth runs along the z axis.
            let mut o = Vec3::from(v(i, 50)) * 3.0;
            let (b1, b2) = (0.3 * (rnd(i, 60) + 1.0), 0.3 * (rnd(i, 61) + 1.0));
            let (aim, _) = triangle_point(&tris[(i / 4 % 4) as usize], b1, b2);
            let mut d = aim - o;
            if i % 4 == 1 {
                d = Vec3::new(0.0, 0.0, d.z.signum());
            }
            // Every fourth ray starts on triangle 2's surface.
            if i % 4 == 2 {
                (o, _) = triangle_point(&tris[2], 0.3, 0.3);
                d = Vec3::from(v(i, 40));
            }
            let ray = Ray { o, d };
            let four = intersect_triangles4(&Ray4::new(&ray), &pack);
            for (l, t) in tris.iter().enumerate() {
                match intersect_triangle(&ray, t) {
                    Some(h) => {
                        hits += 1;
                        assert!(four.mask & (1 << l) != 0, "pack {i} lane {l}: missed");
                        let got = [four.t[l], four.t_err[l], four.b1[l], four.b2[l]];
                        let want = [h.t, h.t_err, h.b1, h.b2];
                        assert_eq!(got.map(f32::to_bits), want.map(f32::to_bits), "{i} {l}");
                    }
                    None => {
                        misses += 1;
                        assert!(four.mask & (1 << l) == 0, "pack {i} lane {l}: false hit");
                    }
                }
            }
            assert_eq!(four.mask >> 4, 0);
        }
        // Both outcomes are exercised in quantity.
        assert!(
            hits > 10_000 && misses > 10_000,
            "{hits} hits, {misses} misses"
        );
    }

    /// A hit on the bottom face of a box right at its edge with the wall x = 1 (where the
    /// bottom face's own point can round onto or past the wall's plane) yields a spawn point
    /// strictly inside the wall's half-space x < 1, moved by no more than a few error bounds.
    /// Power: the unmoved points of the same hits land on x >= 1 for a good share of them.
    #[test]
    fn hit_points_near_an_edge_stay_inside_the_adjacent_face() {
        let tri = Triangle::new([-1.0, -1.0, 1e-4], [1.0, -1.0, 1e-4], [1.0, 1.0, 1e-4], 0);
        let mut unmoved_outside = 0;
        for i in 0..10_000u32 {
            let b1 = crate::math::sampling::u32_to_unit_f32(
                crate::math::sampling::pcg4d([i, 0, 3, 4])[0],
            );
            // b0 = 1 - b1 - b2 exactly 0, or a few ulps either side of it.
            let b2 = 1.0 - b1 + (i % 5) as f32 * 1e-8 - 2e-8;
            let (plain, plain_err) = triangle_point(&tri, b1, b2);
            let (p, p_err) = triangle_hit_point(&tri, b1, b2);
            unmoved_outside += u32::from(plain.x >= 1.0);
            assert!(
                p.x < 1.0,
                "hit {i}: spawn point {p} on or past the wall x = 1"
            );
            let o = offset_ray_origin(p, p_err, triangle_normal(&tri), Vec3::new(1.0, 0.0, 1.0));
            assert!(
                o.x < 1.0,
                "hit {i}: spawned origin {o} on or past the wall x = 1"
            );
            let bound = 8.0 * (plain_err.x + plain_err.y + plain_err.z);
            assert!(
                (p - plain).length() <= bound,
                "hit {i}: moved {}",
                (p - plain).length()
            );
        }
        assert!(
            unmoved_outside > 1_000,
            "{unmoved_outside} unmoved points outside"
        );
    }

    #[test]
    fn sphere_hit_from_outside_and_inside() {
        let s = Sphere {
            center: [0.0, 0.0, 5.0],
            radius: 1.0,
            ..Default::default()
        };
        let from_outside = Ray {
            o: Vec3::ZERO,
            d: Vec3::Z,
        };
        assert!((intersect_sphere(&from_outside, &s).unwrap().t - 4.0).abs() < 1e-5);
        let from_inside = Ray {
            o: Vec3::new(0.0, 0.0, 5.0),
            d: Vec3::Z,
        };
        assert!((intersect_sphere(&from_inside, &s).unwrap().t - 1.0).abs() < 1e-5);
    }
}
