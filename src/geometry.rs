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

use crate::flat::{BvhNode, Sphere, Triangle, EMPTY_SLOT};
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
    let mut po = p + offset;
    for i in 0..3 {
        if offset[i] > 0.0 {
            po[i] = next_float_up(po[i]);
        } else if offset[i] < 0.0 {
            po[i] = next_float_down(po[i]);
        }
    }
    po
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
    /// Unit geometric normal: (v1 - v0) x (v2 - v0) for triangles, outward for spheres.
    pub n: Vec3,
    pub material: u32,
    /// The `prims` entry that was hit (triangle index, or sphere index with the sphere bit).
    pub prim: u32,
}

/// The point of a triangle at barycentrics (b0, b1, b2), with pbrt-v4's bound
/// gamma(7) (|b0 p0| + |b1 p1| + |b2 p2|) on its error (eq. 6.34).
#[inline]
pub fn triangle_point(tri: &Triangle, b1: f32, b2: f32) -> (Vec3, Vec3) {
    let b0 = 1.0 - b1 - b2;
    let (p0, p1, p2) = (Vec3::from(tri.v0), Vec3::from(tri.v1), Vec3::from(tri.v2));
    let p = b0 * p0 + b1 * p1 + b2 * p2;
    let p_err = gamma(7) * ((b0 * p0).abs() + (b1 * p1).abs() + (b2 * p2).abs());
    (p, p_err)
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
    let center = Vec3::from(sphere.center);
    let local = ray.o - center + t * ray.d;
    let local = local * (sphere.radius / local.length());
    let p = center + local;
    let p_err = gamma(5) * local.abs() + gamma(2) * p.abs();
    (p, p_err, local / sphere.radius)
}

/// The slab test (Kay and Kajiya) against the four children's boxes of a BVH node at once, with
/// pbrt-v4's 1 + 2 gamma(3) widening of the far distance so that rounding never culls a box the
/// ray touches. Returns, per child slot, the distance at which the ray enters its box (0 when it
/// starts inside), or -1 when it misses the box, enters it beyond `t_max` or the slot is empty
/// (-1, not infinity, because WGSL has no infinity).
#[inline]
pub fn intersect_aabb4(node: &BvhNode, o: Vec3, inv_d: Vec3, t_max: f32) -> [f32; 4] {
    let slab = |lo: [f32; 4], hi: [f32; 4], o: f32, inv_d: f32| {
        let t_lo = (Vec4::from(lo) - Vec4::splat(o)) * inv_d;
        let t_hi = (Vec4::from(hi) - Vec4::splat(o)) * inv_d;
        (t_lo.min(t_hi), t_lo.max(t_hi))
    };
    let (near_x, far_x) = slab(node.min_x, node.max_x, o.x, inv_d.x);
    let (near_y, far_y) = slab(node.min_y, node.max_y, o.y, inv_d.y);
    let (near_z, far_z) = slab(node.min_z, node.max_z, o.z, inv_d.z);
    let t_near = near_x.max(near_y).max(near_z).max(Vec4::ZERO);
    let t_far = far_x.min(far_y).min(far_z) * (1.0 + 2.0 * gamma(3));
    let t = Vec4::select(
        t_near.cmple(t_far.min(Vec4::splat(t_max))),
        t_near,
        Vec4::splat(-1.0),
    )
    .to_array();
    std::array::from_fn(|c| {
        if node.count[c] == EMPTY_SLOT {
            -1.0
        } else {
            t[c]
        }
    })
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
