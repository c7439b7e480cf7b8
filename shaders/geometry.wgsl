// Ray-primitive intersection with floating-point error bounds, and spawning rays that cannot
// hit the surface they leave: `src/math/geometry.rs`, line for line (pbrt-v4 section 6.8).

struct Ray {
    o: vec3<f32>,
    d: vec3<f32>,
}

// Half an ulp of 1.0 in f32.
const MACHINE_EPSILON: f32 = 5.9604645e-8;

// gamma_n = n eps / (1 - n eps) (pbrt-v4 eq. 6.22).
fn gamma(n: f32) -> f32 {
    return (n * MACHINE_EPSILON) / (1.0 - n * MACHINE_EPSILON);
}

fn next_float_up(v_in: f32) -> f32 {
    if bitcast<u32>(v_in) == 0x7f800000u {
        return v_in;
    }
    var v = v_in;
    if v == 0.0 {
        v = 0.0;
    }
    var bits = bitcast<u32>(v);
    if v >= 0.0 {
        bits += 1u;
    } else {
        bits -= 1u;
    }
    return bitcast<f32>(bits);
}

fn next_float_down(v_in: f32) -> f32 {
    if bitcast<u32>(v_in) == 0xff800000u {
        return v_in;
    }
    var v = v_in;
    if v == 0.0 {
        v = -0.0;
    }
    var bits = bitcast<u32>(v);
    if v > 0.0 {
        bits -= 1u;
    } else {
        bits += 1u;
    }
    return bitcast<f32>(bits);
}

// p moved along the unit geometric normal n past its error box, to the side w leaves to, then
// rounded away from the surface (pbrt-v4's OffsetRayOrigin, eq. 6.28).
fn offset_ray_origin(p: vec3<f32>, p_err: vec3<f32>, n: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    let d = dot(abs(n), p_err);
    var offset = d * n;
    if dot(w, n) < 0.0 {
        offset = -offset;
    }
    var po = p + offset;
    for (var i = 0; i < 3; i++) {
        if offset[i] > 0.0 {
            po[i] = next_float_up(po[i]);
        } else if offset[i] < 0.0 {
            po[i] = next_float_down(po[i]);
        }
    }
    return po;
}

fn abs_cross(a_in: vec3<f32>, b_in: vec3<f32>) -> vec3<f32> {
    let a = abs(a_in);
    let b = abs(b_in);
    return vec3<f32>(a.y * b.z + a.z * b.y, a.z * b.x + a.x * b.z, a.x * b.y + a.y * b.x);
}

struct TriangleHit {
    found: bool,
    t: f32,
    t_err: f32,
    b1: f32,
    b2: f32,
}

// Moller-Trumbore, with t accepted only above its own rounding-error bound.
fn intersect_triangle(ray: Ray, tri: Triangle) -> TriangleHit {
    var miss = TriangleHit(false, 0.0, 0.0, 0.0, 0.0);
    let e1 = tri.v1 - tri.v0;
    let e2 = tri.v2 - tri.v0;
    let pvec = cross(ray.d, e2);
    let det = dot(e1, pvec);
    if det == 0.0 {
        return miss;
    }
    // The barycentrics times |det| (the sign of det folded in) are compared with |det|, so a
    // miss costs no division.
    let sign = select(1.0, -1.0, det < 0.0);
    let abs_det = abs(det);
    let s = ray.o - tri.v0;
    let u = dot(s, pvec) * sign;
    if !(u >= 0.0 && u <= abs_det) {
        return miss;
    }
    let qvec = cross(s, e1);
    let v = dot(ray.d, qvec) * sign;
    if v < 0.0 || u + v > abs_det {
        return miss;
    }
    let inv_det = 1.0 / abs_det;
    let t = dot(e2, qvec) * sign * inv_det;
    let t_err = gamma(7.0) * dot(abs(e2), abs_cross(s, e1)) * inv_det;
    if !(t > t_err) {
        return miss;
    }
    return TriangleHit(true, t, t_err, u * inv_det, v * inv_det);
}

struct SphereHit {
    found: bool,
    t: f32,
    t_err: f32,
}

// Ray-sphere in the careful form of Haines et al. (Ray Tracing Gems, ch. 7).
fn intersect_sphere(ray: Ray, sphere: Sphere) -> SphereHit {
    var miss = SphereHit(false, 0.0, 0.0);
    let r = sphere.radius;
    let f = ray.o - sphere.center;
    let a = dot(ray.d, ray.d);
    let b_half = -dot(f, ray.d);
    let l = f + (b_half / a) * ray.d;
    let disc = a * (r * r - dot(l, l));
    if disc < 0.0 {
        return miss;
    }
    let c = dot(f, f) - r * r;
    let q = b_half + select(-1.0, 1.0, b_half >= 0.0) * sqrt(disc);
    if q == 0.0 {
        return miss;
    }
    let ta = c / q;
    let tb = q / a;
    let t0 = min(ta, tb);
    let t1 = max(ta, tb);
    let c_err = (dot(f, f) + r * r) / abs(q);
    let err0 = gamma(8.0) * (abs(t0) + c_err);
    if t0 > err0 {
        return SphereHit(true, t0, err0);
    }
    let err1 = gamma(8.0) * (abs(t1) + c_err);
    if t1 > err1 {
        return SphereHit(true, t1, err1);
    }
    return miss;
}

struct SurfaceHit {
    t: f32,
    p: vec3<f32>,
    p_err: vec3<f32>,
    n: vec3<f32>,
    material: u32,
    prim: u32,
}

struct PointWithError {
    p: vec3<f32>,
    p_err: vec3<f32>,
}

// The point at barycentrics (b0, b1, b2), with the bound gamma(7) sum |b_i p_i| (pbrt-v4 eq. 6.34).
fn triangle_point(tri: Triangle, b1: f32, b2: f32) -> PointWithError {
    return triangle_point_at(tri, vec3<f32>(1.0 - b1 - b2, b1, b2));
}

// The point of a triangle at barycentrics b = (b0, b1, b2), with the bound
// gamma(7) (|b0 p0| + |b1 p1| + |b2 p2|) on its error.
fn triangle_point_at(tri: Triangle, b: vec3<f32>) -> PointWithError {
    let p = b.x * tri.v0 + b.y * tri.v1 + b.z * tri.v2;
    let p_err = gamma(7.0) * (abs(b.x * tri.v0) + abs(b.y * tri.v1) + abs(b.z * tri.v2));
    return PointWithError(p, p_err);
}

// The point of a triangle hit at (b1, b2), moved into the triangle where it lies closer to an
// edge than its own error bound, for spawning rays from it: each barycentric raised to at least
// m |e_i| / (2A), m twice the L1 norm of the error box, and the three renormalised
// (`triangle_hit_point` in src/math/geometry.rs says why).
fn triangle_hit_point(tri: Triangle, b1: f32, b2: f32) -> PointWithError {
    let pe = triangle_point(tri, b1, b2);
    let b = vec3<f32>(1.0 - b1 - b2, b1, b2);
    let two_area = dot(cross(tri.v1 - tri.v0, tri.v2 - tri.v0), tri.n);
    let margin = 2.0 * (pe.p_err.x + pe.p_err.y + pe.p_err.z);
    let edges = vec3<f32>(
        length(tri.v2 - tri.v1),
        length(tri.v2 - tri.v0),
        length(tri.v1 - tri.v0),
    );
    let least = edges * (margin / two_area);
    if all(b >= least) || !(two_area > 0.0) {
        return pe;
    }
    let raised = max(b, least);
    return triangle_point_at(tri, raised / (raised.x + raised.y + raised.z));
}

// The unit geometric normal, stored with the triangle (`Triangle::new`).
fn triangle_normal(tri: Triangle) -> vec3<f32> {
    return tri.n;
}

// The unit normal at a unit direction d from the centre: d, or -d when flipped (`Sphere::normal`).
fn sphere_normal(sphere: Sphere, d: vec3<f32>) -> vec3<f32> {
    return select(d, -d, sphere.flip != 0u);
}

// A sphere hit projected back onto the sphere; the bound is gamma(5)|p_local| plus the
// rounding of adding the centre back.
fn sphere_point(ray: Ray, sphere: Sphere, t: f32) -> SurfaceHit {
    var local = ray.o - sphere.center + t * ray.d;
    local = local * (sphere.radius / length(local));
    let pe = sphere_point_at(sphere, local);
    return SurfaceHit(t, pe.p, pe.p_err, sphere_normal(sphere, local / sphere.radius), sphere.material, 0u);
}

// The point at offset `local` from a sphere's centre and its error bound (`sphere_point_at`),
// shared by hits and sampled emitter points.
fn sphere_point_at(sphere: Sphere, local: vec3<f32>) -> PointWithError {
    let p = sphere.center + local;
    return PointWithError(p, gamma(5.0) * abs(local) + gamma(2.0) * abs(p));
}

// The slab test against the four children's boxes of a node at once, with pbrt-v4's
// 1 + 2 gamma(3) widening of the far distance. Per child slot: the distance at which the ray
// enters the box (0 inside), or -1 when it misses, enters beyond t_max or the slot is empty.
// The CPU's is `geometry::intersect_boxes4`, which its wide nodes call once per row of four.
fn intersect_aabb4(node: BvhNode, o: vec3<f32>, inv_d: vec3<f32>, t_max: f32) -> vec4<f32> {
    let lo_x = (node.min_x - o.x) * inv_d.x;
    let hi_x = (node.max_x - o.x) * inv_d.x;
    let lo_y = (node.min_y - o.y) * inv_d.y;
    let hi_y = (node.max_y - o.y) * inv_d.y;
    let lo_z = (node.min_z - o.z) * inv_d.z;
    let hi_z = (node.max_z - o.z) * inv_d.z;
    let t_near = max(max(max(min(lo_x, hi_x), min(lo_y, hi_y)), min(lo_z, hi_z)), vec4<f32>(0.0));
    let t_far = min(min(max(lo_x, hi_x), max(lo_y, hi_y)), max(lo_z, hi_z)) * (1.0 + 2.0 * gamma(3.0));
    let hit = (t_near <= min(t_far, vec4<f32>(t_max))) & (node.count != vec4<u32>(EMPTY_SLOT));
    return select(vec4<f32>(-1.0), t_near, hit);
}

// 1/d with zero components nudged to 1e-30 (keeping the sign), so the slab test never
// computes 0 x inf.
fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    var n = d;
    for (var i = 0; i < 3; i++) {
        if abs(n[i]) < 1e-30 {
            n[i] = select(1e-30, -1e-30, bitcast<u32>(n[i]) >= 0x80000000u);
        }
    }
    return 1.0 / n;
}
