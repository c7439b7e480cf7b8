//! Ray packets: up to eight rays traversed together, one per lane of a 256-bit vector.
//!
//! The CPU's scalar traversal ([`crate::accel::bvh`]) pays, per ray, for a chain of dependent
//! test-decide-load steps and their mispredicted branches (docs/journal/2026-11-26_packets.md). A
//! packet walks the same eight-wide tree once for all its rays: a child is entered when any active
//! lane's slab test passes, and a leaf's triangles are each tested against the eight rays at once,
//! the triangle's coordinates broadcast to every lane. Branches then depend on eight rays' union,
//! not on one ray's path, and the arithmetic fills the vector. The union costs work on incoherent
//! rays: on the reference scenes a packet of diffuse bounce rays takes 0.79 – 0.88 of the scalar
//! time per ray, a packet of shadow rays toward the lights 0.32 – 0.39 (`examples/packet_rays.rs`;
//! docs/design/cpu.md, "Packets").
//!
//! Each lane's arithmetic is the scalar test's, operation for operation and with the same NaN
//! behaviour of every comparison and min/max ([`crate::math::geometry::intersect_triangles4`],
//! [`crate::math::geometry::intersect_boxes4`], [`crate::math::geometry::intersect_sphere`]), so a
//! packet reports each ray's hits with the same t and barycentrics, and the same nearest: of hits
//! at the same t, both keep the lower primitive id ([`crate::accel::bvh::nearer`], which says where
//! the order can still decide). Each lane's nearest so far lives in vectors and is replaced by
//! blends, and a node's eight slab tests come before its children are visited, so that few branches
//! depend on which lanes hit (docs/journal/2026-11-27_branches.md).
//!
//! A packet's closest-hit traversal visits the children a lane enters nearest first (by the least
//! entry distance of the lanes that enter each), so that a large tree's far subtrees are culled by
//! the hits found first. Where only [`SINGLE_RAY_LANES`] of the packet's rays enter a subtree, those
//! rays go on alone below it ([`crate::accel::bvh::closest_below`],
//! [`crate::accel::bvh::occluded_below`]): deep in a large mesh the rays of a packet part ways, and
//! a node costs one ray a quarter of the packet's slab tests (Benthin et al. 2012, "Combining single
//! and packet-ray tracing for arbitrary ray distributions on the Intel MIC architecture").
//!
//! Needs AVX (checked at run time, so the portable build uses it too); elsewhere each ray takes
//! the scalar traversal.

use crate::accel::bvh::{intersect_closest, occluded};
use crate::layout::FlatScene;
use crate::math::geometry::{Ray, SurfaceHit};
use crate::math::lanes::{lanes_of, F8, V8};

/// The most rays a packet holds.
pub const PACKET: usize = 8;

/// Trees of more four-wide nodes than this are large: there a packet's closest-hit traversal
/// visits children nearest first, and rays go on alone below a node that few of them enter. In
/// a small tree a packet's rays stay coherent down to the leaves, and both cost more than they
/// save: with them the three reference rooms (a few nodes each) ran at 0.94 – 0.97x the camera
/// paths/s; with them on large trees only, bunny_room and bunny_room_1m run at 1.40x and
/// 1.35x, the rooms level (docs/journal/2026-11-29_meshes.md).
pub const LARGE_TREE_NODES: usize = 64;

/// In a large tree ([`LARGE_TREE_NODES`]), a subtree that at most this many of a packet's rays
/// enter is traversed by each of them alone. One lane: with two, a render of bunny_room_1m ran at
/// 0.96 of the camera paths/s, bunny_room at 0.98 and tncg15_room at 0.94
/// (docs/journal/2026-11-29_meshes.md).
pub const SINGLE_RAY_LANES: u32 = 1;

/// The nearest hit of each ray (`t` in (its error bound, f32::MAX)), as
/// [`intersect_closest`] finds it, for any number of rays, in packets of eight where the CPU has
/// AVX, else one by one.
pub fn intersect_closest_packets(scene: &FlatScene, rays: &[Ray], hits: &mut [Option<SurfaceHit>]) {
    assert_eq!(rays.len(), hits.len());
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        for (r, h) in rays.chunks(PACKET).zip(hits.chunks_mut(PACKET)) {
            // SAFETY: the CPU has AVX (checked above).
            unsafe { avx::closest(scene, r, h) };
        }
        return;
    }
    for (r, h) in rays.iter().zip(hits.iter_mut()) {
        *h = intersect_closest(scene, r, f32::MAX);
    }
}

/// Whether anything lies on each shadow segment `o + t d`, t in (0, 1), as [`occluded`]
/// decides it, for any number of rays, eight at a time.
pub fn occluded_all(scene: &FlatScene, rays: &[Ray], blocked: &mut [bool]) {
    assert_eq!(rays.len(), blocked.len());
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        for (r, b) in rays.chunks(PACKET).zip(blocked.chunks_mut(PACKET)) {
            // SAFETY: the CPU has AVX (checked above).
            unsafe { avx::occluded(scene, r, b) };
        }
        return;
    }
    for (r, b) in rays.iter().zip(blocked.iter_mut()) {
        *b = occluded(scene, r, 1.0);
    }
}

/// Eight rays' nearest hits in rows: the lanes that hit something (`hit`, bits) and, in those,
/// what [`SurfaceHit`] holds.
#[derive(Clone, Copy, Debug, Default)]
pub struct HitLanes {
    pub hit: u32,
    pub t: F8,
    pub p: V8,
    pub p_err: V8,
    pub n: V8,
    pub material: [u32; PACKET],
    pub prim: [u32; PACKET],
}

impl HitLanes {
    /// Lane `l`'s hit (which must be one of `hit`'s).
    #[inline]
    pub fn get(&self, l: usize) -> SurfaceHit {
        SurfaceHit {
            t: self.t.as_array()[l],
            p: self.p.lane(l),
            p_err: self.p_err.lane(l),
            n: self.n.lane(l),
            material: self.material[l],
            prim: self.prim[l],
        }
    }

    /// Lane `l` set to `hit`.
    #[inline]
    fn set(&mut self, l: usize, hit: Option<SurfaceHit>) {
        let Some(h) = hit else {
            self.hit &= !(1 << l);
            return;
        };
        self.hit |= 1 << l;
        self.t.as_mut_array()[l] = h.t;
        self.p.set_lane(l, h.p);
        self.p_err.set_lane(l, h.p_err);
        self.n.set_lane(l, h.n);
        self.material[l] = h.material;
        self.prim[l] = h.prim;
    }
}

/// The nearest hit of each ray in `lanes` (bits) of eight rays given as rows (`o`, `d`: a
/// coordinate of every lane per row, as a wavefront holds them in structure-of-arrays form),
/// as [`intersect_closest`] finds it, in rows: one packet, without gathering the rays, where
/// the CPU has AVX, its triangle hits' points computed in lanes
/// ([`crate::math::lanes::triangle_hit_point`]); else lane by lane. A lane outside `lanes` hits
/// nothing.
pub fn intersect_closest_lanes(scene: &FlatScene, (o, d): (&V8, &V8), lanes: u32) -> HitLanes {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX (checked above).
        return unsafe { avx::closest_lanes(scene, (o, d), lanes) };
    }
    let mut hits = HitLanes::default();
    for l in lanes_of(lanes) {
        hits.set(l, intersect_closest(scene, &ray_of((o, d), l), f32::MAX));
    }
    hits
}

/// Lane `l`'s ray of eight rays in rows.
#[inline]
fn ray_of((o, d): (&V8, &V8), l: usize) -> Ray {
    Ray {
        o: o.lane(l),
        d: d.lane(l),
    }
}

/// Of eight shadow segments given as rows (`o + t d`, t in (0, 1)), those in `lanes` (bits)
/// that something blocks, as bits, as [`occluded`] decides it: one packet where the CPU has
/// AVX, else lane by lane.
pub fn occluded_lanes(scene: &FlatScene, (o, d): (&V8, &V8), lanes: u32) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX (checked above).
        return unsafe { avx::occluded_lanes(scene, (o, d), lanes) };
    }
    lanes_of(lanes)
        .filter(|&l| occluded(scene, &ray_of((o, d), l), 1.0))
        .fold(0, |bits, l| bits | 1 << l)
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::{ray_of, HitLanes, LARGE_TREE_NODES};
    use crate::accel::bvh::{
        closest_below, occluded_below, surface_hit, Candidate, WIDE_STACK_SIZE,
    };
    use crate::layout::{FlatScene, Sphere, EMPTY_SLOT, PRIM_SPHERE_BIT};
    use crate::math::geometry::{gamma, Ray, SurfaceHit};
    use crate::math::lanes::lanes_of;
    use crate::math::lanes::{F8, V8};
    use std::arch::x86_64::*;

    /// Up to eight rays, a coordinate per vector, and what the traversal keeps per lane.
    struct Packet {
        o: [__m256; 3],
        d: [__m256; 3],
        inv_d: [__m256; 3],
        /// Lanes still looking (a lane past the packet's rays never is; an any-hit lane stops
        /// at its first hit).
        active: i32,
    }

    #[inline]
    #[target_feature(enable = "avx")]
    fn load(rays: &[Ray]) -> Packet {
        let mut c = [[0.0f32; 8]; 6];
        for l in 0..8 {
            // Lanes past the rays repeat the last ray and stay inactive.
            let r = &rays[l.min(rays.len() - 1)];
            for a in 0..3 {
                c[a][l] = r.o[a];
                c[3 + a][l] = r.d[a];
            }
        }
        // SAFETY: each array holds eight f32.
        let v = c.map(|a| unsafe { _mm256_loadu_ps(a.as_ptr()) });
        from_rows(
            [v[0], v[1], v[2]],
            [v[3], v[4], v[5]],
            (1 << rays.len()) - 1,
        )
    }

    /// A coordinate row of eight lanes as a vector.
    #[inline]
    #[target_feature(enable = "avx")]
    fn row(x: &crate::math::lanes::F8) -> __m256 {
        let a: [f32; 8] = bytemuck::cast(*x);
        // SAFETY: eight f32.
        unsafe { _mm256_loadu_ps(a.as_ptr()) }
    }

    /// The packet of the rays `o + t d` of eight lanes' rows, the lanes `lanes` (bits) looking.
    #[inline]
    #[target_feature(enable = "avx")]
    fn from_lanes((o, d): (&V8, &V8), lanes: u32) -> Packet {
        from_rows(
            [row(&o.x), row(&o.y), row(&o.z)],
            [row(&d.x), row(&d.y), row(&d.z)],
            lanes as i32,
        )
    }

    /// The packet of rays `o + t d` in rows, the lanes `active` (bits) looking: each lane's
    /// inverse direction is `safe_inverse`'s, operation for operation (a component below 1e-30
    /// in magnitude replaced by 1e-30 of its sign, then 1 / d).
    #[inline]
    #[target_feature(enable = "avx")]
    fn from_rows(o: [__m256; 3], d: [__m256; 3], active: i32) -> Packet {
        let inv_d = d.map(|x| {
            let is_tiny = _mm256_cmp_ps::<_CMP_LT_OS>(abs(x), _mm256_set1_ps(1e-30));
            let nudged = _mm256_blendv_ps(x, with_sign_of(1e-30, x), is_tiny);
            _mm256_div_ps(_mm256_set1_ps(1.0), nudged)
        });
        Packet {
            o,
            d,
            inv_d,
            active,
        }
    }

    /// The slab test of every lane's ray against one box (`intersect_boxes4`'s arithmetic, the
    /// box broadcast instead of the ray): each lane's entry distance and its exit distance
    /// widened by the test's error bound; [`within`] compares them with a limit.
    #[inline]
    #[target_feature(enable = "avx")]
    fn span(p: &Packet, lo: [f32; 3], hi: [f32; 3]) -> (__m256, __m256) {
        let mut near = [_mm256_setzero_ps(); 3];
        let mut far = [_mm256_setzero_ps(); 3];
        for a in 0..3 {
            let t_lo = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(lo[a]), p.o[a]), p.inv_d[a]);
            let t_hi = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(hi[a]), p.o[a]), p.inv_d[a]);
            near[a] = _mm256_min_ps(t_lo, t_hi);
            far[a] = _mm256_max_ps(t_lo, t_hi);
        }
        let t_near = _mm256_max_ps(
            _mm256_max_ps(_mm256_max_ps(near[0], near[1]), near[2]),
            _mm256_setzero_ps(),
        );
        let t_far = _mm256_mul_ps(
            _mm256_min_ps(_mm256_min_ps(far[0], far[1]), far[2]),
            _mm256_set1_ps(1.0 + 2.0 * gamma(3)),
        );
        (t_near, t_far)
    }

    /// The lanes whose span starts no later than its end and `t_max`, as a vector mask.
    #[inline]
    #[target_feature(enable = "avx")]
    fn within((t_near, t_far): (__m256, __m256), t_max: __m256) -> __m256 {
        _mm256_cmp_ps::<_CMP_LE_OS>(t_near, _mm256_min_ps(t_far, t_max))
    }

    /// |x| in every lane: the sign bit cleared, as `f32::abs`.
    #[inline]
    #[target_feature(enable = "avx")]
    fn abs(x: __m256) -> __m256 {
        _mm256_andnot_ps(_mm256_set1_ps(-0.0), x)
    }

    /// copysign(magnitude, x) in every lane, for a non-negative `magnitude`: it with x's sign
    /// bit.
    #[inline]
    #[target_feature(enable = "avx")]
    fn with_sign_of(magnitude: f32, x: __m256) -> __m256 {
        _mm256_or_ps(
            _mm256_and_ps(x, _mm256_set1_ps(-0.0)),
            _mm256_set1_ps(magnitude),
        )
    }

    /// copysign(1, x) in every lane: 1 with x's sign bit.
    #[inline]
    #[target_feature(enable = "avx")]
    fn sign_one(x: __m256) -> __m256 {
        with_sign_of(1.0, x)
    }

    /// One triangle against every lane's ray: `intersect_triangle`'s Möller–Trumbore with the
    /// same operations in the same order (no fused multiply-adds), t, its error bound and the
    /// barycentrics, and the mask of the lanes that hit it.
    struct TriangleHits8 {
        hit: __m256,
        t: __m256,
        t_err: __m256,
        b1: __m256,
        b2: __m256,
    }

    #[inline]
    #[target_feature(enable = "avx")]
    fn triangle(p: &Packet, v0: [f32; 3], e1: [f32; 3], e2: [f32; 3]) -> TriangleHits8 {
        let s = |x: f32| _mm256_set1_ps(x);
        let (mul, sub, add) = (_mm256_mul_ps, _mm256_sub_ps, _mm256_add_ps);
        let [ox, oy, oz] = p.o;
        let [dx, dy, dz] = p.d;
        let ([v0x, v0y, v0z], [e1x, e1y, e1z], [e2x, e2y, e2z]) = (v0.map(s), e1.map(s), e2.map(s));
        // pvec = d x e2, det = e1 . pvec
        let px = sub(mul(dy, e2z), mul(e2y, dz));
        let py = sub(mul(dz, e2x), mul(e2z, dx));
        let pz = sub(mul(dx, e2y), mul(e2x, dy));
        let det = add(add(mul(e1x, px), mul(e1y, py)), mul(e1z, pz));
        let sign = sign_one(det);
        let abs_det = abs(det);
        // s = o - v0, u = (s . pvec) sign
        let (sx, sy, sz) = (sub(ox, v0x), sub(oy, v0y), sub(oz, v0z));
        let u = mul(add(add(mul(sx, px), mul(sy, py)), mul(sz, pz)), sign);
        // qvec = s x e1, v = (d . qvec) sign
        let qx = sub(mul(sy, e1z), mul(e1y, sz));
        let qy = sub(mul(sz, e1x), mul(e1z, sx));
        let qz = sub(mul(sx, e1y), mul(e1x, sy));
        let v = mul(add(add(mul(dx, qx), mul(dy, qy)), mul(dz, qz)), sign);
        let inv_det = _mm256_div_ps(s(1.0), abs_det);
        let t = mul(
            mul(add(add(mul(e2x, qx), mul(e2y, qy)), mul(e2z, qz)), sign),
            inv_det,
        );
        // t_err = gamma(7) (|e2| . (|s| x |e1|)) / |det|
        let (ax, ay, az) = (abs(sx), abs(sy), abs(sz));
        let (bx, by, bz) = (abs(e1x), abs(e1y), abs(e1z));
        let (cx, cy, cz) = (
            add(mul(ay, bz), mul(az, by)),
            add(mul(az, bx), mul(ax, bz)),
            add(mul(ax, by), mul(ay, bx)),
        );
        let t_err = mul(
            mul(
                s(gamma(7)),
                add(add(mul(abs(e2x), cx), mul(abs(e2y), cy)), mul(abs(e2z), cz)),
            ),
            inv_det,
        );
        // The scalar test's exits as masks, each NaN-true or NaN-false as there.
        let and = _mm256_and_ps;
        let hit = and(
            and(
                and(
                    _mm256_cmp_ps::<_CMP_NEQ_UQ>(det, s(0.0)),
                    _mm256_cmp_ps::<_CMP_GE_OS>(u, s(0.0)),
                ),
                and(
                    _mm256_cmp_ps::<_CMP_LE_OS>(u, abs_det),
                    _mm256_cmp_ps::<_CMP_NLT_US>(v, s(0.0)),
                ),
            ),
            and(
                _mm256_cmp_ps::<_CMP_NGT_US>(add(u, v), abs_det),
                _mm256_cmp_ps::<_CMP_GT_OS>(t, t_err),
            ),
        );
        TriangleHits8 {
            hit,
            t,
            t_err,
            b1: mul(u, inv_det),
            b2: mul(v, inv_det),
        }
    }

    /// One sphere against every lane's ray: `intersect_sphere` with the same operations in the
    /// same order, its two exits as masks (NaN-true or NaN-false as there), and of its roots
    /// the one it returns, with its error bound.
    struct SphereHits8 {
        hit: __m256,
        t: __m256,
        t_err: __m256,
    }

    #[inline]
    #[target_feature(enable = "avx")]
    fn sphere(p: &Packet, sphere: &Sphere) -> SphereHits8 {
        let s = |x: f32| _mm256_set1_ps(x);
        let (mul, sub, add, div) = (_mm256_mul_ps, _mm256_sub_ps, _mm256_add_ps, _mm256_div_ps);
        let dot = |a: [__m256; 3], b: [__m256; 3]| {
            add(add(mul(a[0], b[0]), mul(a[1], b[1])), mul(a[2], b[2]))
        };
        let r = s(sphere.radius);
        let center = sphere.center.map(s);
        let f = [0, 1, 2].map(|a| sub(p.o[a], center[a]));
        let a = dot(p.d, p.d);
        // -f . d, negated by its sign bit as Rust's unary minus
        let b_half = _mm256_xor_ps(dot(f, p.d), s(-0.0));
        let scale = div(b_half, a);
        let l = [0, 1, 2].map(|k| add(f[k], mul(scale, p.d[k])));
        let disc = mul(a, sub(mul(r, r), dot(l, l)));
        let c = sub(dot(f, f), mul(r, r));
        // signum(b_half) as copysign(1, b_half): the same but for a NaN b_half, where q is NaN
        // either way
        let sign = sign_one(b_half);
        let q = add(b_half, mul(sign, _mm256_sqrt_ps(disc)));
        let (ta, tb) = (div(c, q), div(q, a));
        let in_order = _mm256_cmp_ps::<_CMP_LE_OQ>(ta, tb);
        let (t0, t1) = (
            _mm256_blendv_ps(tb, ta, in_order),
            _mm256_blendv_ps(ta, tb, in_order),
        );
        let c_err = div(add(dot(f, f), mul(r, r)), abs(q));
        let err0 = mul(s(gamma(8)), add(abs(t0), c_err));
        let err1 = mul(s(gamma(8)), add(abs(t1), c_err));
        let first = _mm256_cmp_ps::<_CMP_GT_OQ>(t0, err0);
        let second = _mm256_cmp_ps::<_CMP_GT_OQ>(t1, err1);
        // `disc < 0` and `q == 0` return None; a NaN passes both, as there
        let valid = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_NLT_UQ>(disc, s(0.0)),
            _mm256_cmp_ps::<_CMP_NEQ_UQ>(q, s(0.0)),
        );
        SphereHits8 {
            hit: _mm256_and_ps(valid, _mm256_or_ps(first, second)),
            t: _mm256_blendv_ps(t1, t0, first),
            t_err: _mm256_blendv_ps(err1, err0, first),
        }
    }

    #[inline]
    #[target_feature(enable = "avx")]
    fn lanes(v: __m256) -> [f32; 8] {
        let mut out = [0.0; 8];
        // SAFETY: eight f32 to an array of eight.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), v) };
        out
    }

    /// Calls `leaf(state, packet, t_limit, first, end, lanes, mask)` for every leaf of the wide
    /// tree that one of the packet's active lanes enters before its `t_limit`, `lanes` the bits
    /// of those and `mask` the lanes (active or not) that enter it; the leaf may lower the
    /// limits and deactivate lanes. A leaf's hits count only for the lanes that enter its box,
    /// as in `bvh`. In a large tree ([`super::LARGE_TREE_NODES`]) a subtree that at most
    /// [`super::SINGLE_RAY_LANES`] active lanes enter goes to `single(state, packet, t_limit,
    /// node, lanes)` instead, which traces those lanes alone, and in closest-hit mode (`CLOSEST`)
    /// the interior children are visited nearest first, a popped node that every active lane's
    /// nearest hit has since passed dropped. Otherwise, and in any-hit mode, slot order (ordered,
    /// shadow packets took 1.2 – 1.6 times as long in `examples/packet_rays.rs`: any hit stops a
    /// lane, so the order culls nothing).
    #[inline]
    #[target_feature(enable = "avx")]
    fn traverse<const CLOSEST: bool, const LARGE: bool, S>(
        scene: &FlatScene,
        p: &mut Packet,
        t_limit: &mut __m256,
        state: &mut S,
        mut leaf: impl FnMut(&mut S, &mut Packet, &mut __m256, usize, usize, i32, __m256),
        mut single: impl FnMut(&mut S, &mut Packet, &mut __m256, u32, i32),
    ) {
        // Interior nodes still to visit, each with the least entry distance of the lanes that
        // entered it (closest-hit mode) and those lanes: at most seven net pushes a level, as in
        // `bvh`. (Not an array zeroed per traversal: writing it costs more than a small tree's
        // whole traversal of a shadow packet.)
        let mut stack = arrayvec::ArrayVec::<u32, { WIDE_STACK_SIZE + 1 }>::new();
        // Beside each entry of `stack` in a large tree: (key, lanes).
        let mut keys = arrayvec::ArrayVec::<(f32, i32), { WIDE_STACK_SIZE + 1 }>::new();
        stack.push(0);
        if LARGE {
            keys.push((0.0, p.active));
        }
        while p.active != 0 {
            let Some(index) = stack.pop() else {
                break;
            };
            let (key, entering) = if LARGE {
                keys.pop().unwrap_or_default()
            } else {
                (0.0, p.active)
            };
            // (The nearest hit of every active lane has since passed the node's box.)
            if LARGE
                && CLOSEST
                && _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(_mm256_set1_ps(key), *t_limit))
                    & p.active
                    == 0
            {
                continue;
            }
            if LARGE && (entering & p.active).count_ones() <= super::SINGLE_RAY_LANES {
                single(state, p, t_limit, index, entering & p.active);
                continue;
            }
            let node = &scene.wide[index as usize];
            // Every occupied slot's slab test first (a node's empty slots come after its
            // children, `bvh::build_trees`), without a branch on its outcome: the children
            // that an active lane enters, as bits, and each one's entry and exit distances.
            let mut spans =
                [(_mm256_setzero_ps(), _mm256_setzero_ps()); crate::accel::wide_bvh::WIDTH];
            let mut children = 0u32;
            for (c, span_c) in spans.iter_mut().enumerate() {
                if node.count[c] == EMPTY_SLOT {
                    break;
                }
                let (lo, hi) = node.child_bounds(c);
                *span_c = span(p, lo.to_array(), hi.to_array());
                let entered = _mm256_movemask_ps(within(*span_c, *t_limit)) & p.active;
                children |= u32::from(entered != 0) << c;
            }
            let mut inner =
                arrayvec::ArrayVec::<(f32, u32, i32), { crate::accel::wide_bvh::WIDTH }>::new();
            // Then those children in slot order, each against the limit as it stands when its
            // turn comes: a leaf before it may have lowered the limit, and a lower limit enters
            // no child that the first test did not.
            while children != 0 {
                let c = children.trailing_zeros() as usize;
                children &= children - 1;
                let count = node.count[c];
                let mask = within(spans[c], *t_limit);
                let entered = _mm256_movemask_ps(mask) & p.active;
                if entered == 0 {
                    continue;
                }
                if count == 0 {
                    if LARGE && CLOSEST {
                        // The child's key: the least entry distance of the lanes entering it.
                        let near = _mm256_blendv_ps(
                            _mm256_set1_ps(f32::INFINITY),
                            spans[c].0,
                            _mm256_and_ps(mask, bits_to_mask(p.active)),
                        );
                        inner.push((hmin(near), node.child[c], entered));
                    } else {
                        stack.push(node.child[c]);
                        if LARGE {
                            keys.push((0.0, entered));
                        }
                    }
                } else {
                    let first = node.child[c] as usize;
                    leaf(
                        state,
                        p,
                        t_limit,
                        first,
                        first + count as usize,
                        entered,
                        mask,
                    );
                    if p.active == 0 {
                        return;
                    }
                }
            }
            // Pushed farthest first, so that the nearest is visited first.
            for i in 1..inner.len() {
                let mut j = i;
                while j > 0 && inner[j - 1].0 < inner[j].0 {
                    inner.swap(j - 1, j);
                    j -= 1;
                }
            }
            for (k, n, e) in inner {
                stack.push(n);
                keys.push((k, e));
            }
        }
    }

    /// The packet's origins and directions as rows of eight, for [`ray_at`].
    #[inline]
    #[target_feature(enable = "avx")]
    fn rows(p: &Packet) -> [[[f32; 8]; 3]; 2] {
        [
            [lanes(p.o[0]), lanes(p.o[1]), lanes(p.o[2])],
            [lanes(p.d[0]), lanes(p.d[1]), lanes(p.d[2])],
        ]
    }

    /// Lane `l`'s ray of a packet's [`rows`].
    #[inline(always)]
    fn ray_at([o, d]: &[[[f32; 8]; 3]; 2], l: usize) -> Ray {
        Ray {
            o: glam::Vec3::new(o[0][l], o[1][l], o[2][l]),
            d: glam::Vec3::new(d[0][l], d[1][l], d[2][l]),
        }
    }

    /// The least of a vector's lanes.
    #[inline]
    #[target_feature(enable = "avx")]
    fn hmin(v: __m256) -> f32 {
        let m = _mm256_min_ps(v, _mm256_permute2f128_ps::<1>(v, v));
        let m = _mm256_min_ps(m, _mm256_shuffle_ps::<0b01_00_11_10>(m, m));
        let m = _mm256_min_ps(m, _mm256_shuffle_ps::<0b10_11_00_01>(m, m));
        _mm256_cvtss_f32(m)
    }

    /// Every lane's nearest hit so far: its barycentrics and its primitive's id (`NO_PRIM`
    /// while there is none), its t being the traversal's `t_limit`.
    struct Nearest {
        b1: __m256,
        b2: __m256,
        /// The ids' bits in float lanes, so that a blend moves them.
        prim: __m256,
    }

    /// No primitive: a lane that has hit nothing yet.
    const NO_PRIM: u32 = u32::MAX;

    /// The vector mask of the lanes whose bits are set in `bits`.
    #[inline]
    #[target_feature(enable = "avx")]
    fn bits_to_mask(bits: i32) -> __m256 {
        let m: [u32; 8] = std::array::from_fn(|l| if bits & (1 << l) != 0 { u32::MAX } else { 0 });
        // SAFETY: eight u32 are eight f32's bits.
        unsafe { _mm256_loadu_ps(m.as_ptr().cast()) }
    }

    #[inline]
    #[target_feature(enable = "avx")]
    fn prims(v: __m256) -> [u32; 8] {
        lanes(v).map(f32::to_bits)
    }

    /// Where a primitive's hits (`candidate`: the lanes that hit it among the packet's rays
    /// that entered its leaf) are nearer than each lane's nearest so far, or as near and of a
    /// lower id (`bvh::nearer`), they replace it: by a blend; ties, rare, lane by lane.
    #[inline]
    #[target_feature(enable = "avx")]
    fn keep_nearer(
        best: &mut Nearest,
        t_limit: &mut __m256,
        candidate: __m256,
        (t, b1, b2): (__m256, __m256, __m256),
        prim: u32,
    ) {
        let mut won = _mm256_and_ps(candidate, _mm256_cmp_ps::<_CMP_LT_OS>(t, *t_limit));
        let tie = _mm256_and_ps(candidate, _mm256_cmp_ps::<_CMP_EQ_OQ>(t, *t_limit));
        let mut tied = _mm256_movemask_ps(tie);
        if tied != 0 {
            let held = prims(best.prim);
            let mut tie_won = 0;
            while tied != 0 {
                let l = tied.trailing_zeros() as usize;
                tied &= tied - 1;
                if held[l] != NO_PRIM && prim < held[l] {
                    tie_won |= 1 << l;
                }
            }
            won = _mm256_or_ps(won, bits_to_mask(tie_won));
        }
        *t_limit = _mm256_blendv_ps(*t_limit, t, won);
        best.b1 = _mm256_blendv_ps(best.b1, b1, won);
        best.b2 = _mm256_blendv_ps(best.b2, b2, won);
        best.prim = _mm256_blendv_ps(best.prim, _mm256_set1_ps(f32::from_bits(prim)), won);
    }

    /// `intersect_closest` for up to eight rays. Each lane's nearest hit so far is kept in
    /// vectors (`Nearest`, its t in `t_limit`) and replaced by a blend where a triangle is
    /// nearer, so that a leaf's triangles take no branch on which lanes they won.
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[target_feature(enable = "avx")]
    pub unsafe fn closest(scene: &FlatScene, rays: &[Ray], hits: &mut [Option<SurfaceHit>]) {
        let (t, b1, b2, held) = closest_in(scene, load(rays));
        for (l, h) in hits.iter_mut().enumerate() {
            *h = (held[l] != NO_PRIM).then(|| {
                let c = Candidate {
                    t: t[l],
                    prim: held[l],
                    b1: b1[l],
                    b2: b2[l],
                };
                surface_hit(scene, &rays[l], c)
            });
        }
    }

    /// [`closest`] for the lanes `lanes` of eight rays in rows, the hits in rows: the
    /// triangles' points in lanes, where the scalar `triangle_hit_point` would not move them
    /// inward (nearly everywhere), the others' and the spheres' lane by lane.
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[target_feature(enable = "avx")]
    pub unsafe fn closest_lanes(scene: &FlatScene, (o, d): (&V8, &V8), lanes: u32) -> HitLanes {
        let (t, b1, b2, held) = closest_in(scene, from_lanes((o, d), lanes));
        let mut hits = HitLanes {
            t: F8::new(t),
            prim: held,
            ..HitLanes::default()
        };
        let (mut triangles, mut others) = (0u32, 0u32);
        for (l, &prim) in held.iter().enumerate() {
            if prim == NO_PRIM {
                continue;
            }
            hits.hit |= 1 << l;
            if prim & PRIM_SPHERE_BIT == 0 {
                triangles |= 1 << l;
            } else {
                others |= 1 << l;
            }
        }
        if triangles != 0 {
            // Every lane's triangle (a lane without one repeats the first that has one).
            let first = held[triangles.trailing_zeros() as usize];
            let index = crate::math::lanes::uints(|l| {
                if triangles & (1 << l) != 0 {
                    held[l]
                } else {
                    first
                }
            });
            let corner = |offset| V8::gather_from(&scene.triangles, index, offset);
            let (p0, p1, p2, n) = (corner(0), corner(4), corner(8), corner(12));
            let (point, p_err, kept) =
                crate::math::lanes::triangle_hit_point(&p0, &p1, &p2, &n, F8::new(b1), F8::new(b2));
            (hits.p, hits.p_err, hits.n) = (point, p_err, n);
            for (l, &i) in index.as_array().iter().enumerate() {
                hits.material[l] = scene.triangles[i as usize].material;
            }
            others |= triangles & !kept.to_bitmask();
        }
        for l in lanes_of(others) {
            let c = Candidate {
                t: t[l],
                prim: held[l],
                b1: b1[l],
                b2: b2[l],
            };
            hits.set(l, Some(surface_hit(scene, &ray_of((o, d), l), c)));
        }
        hits
    }

    /// [`closest_packet`] for the size of the scene's tree ([`LARGE_TREE_NODES`]).
    #[inline]
    #[target_feature(enable = "avx")]
    fn closest_in(scene: &FlatScene, p: Packet) -> ([f32; 8], [f32; 8], [f32; 8], [u32; 8]) {
        if scene.nodes.len() > LARGE_TREE_NODES {
            closest_packet::<true>(scene, p)
        } else {
            closest_packet::<false>(scene, p)
        }
    }

    /// The traversal of [`closest`]: each lane's nearest t, barycentrics and primitive
    /// (`NO_PRIM` where none); `LARGE`, the tree is large ([`LARGE_TREE_NODES`]).
    #[inline]
    #[target_feature(enable = "avx")]
    fn closest_packet<const LARGE: bool>(
        scene: &FlatScene,
        mut p: Packet,
    ) -> ([f32; 8], [f32; 8], [f32; 8], [u32; 8]) {
        let mut t_limit = _mm256_set1_ps(f32::MAX);
        let mut best = Nearest {
            b1: _mm256_setzero_ps(),
            b2: _mm256_setzero_ps(),
            prim: _mm256_set1_ps(f32::from_bits(NO_PRIM)),
        };
        // The packet's rays: the lanes past them never take a hit (closest-hit lanes stay
        // active to the end).
        let rays_mask = bits_to_mask(p.active);
        let leaf = |best: &mut Nearest,
                    p: &mut Packet,
                    t_limit: &mut __m256,
                    first: usize,
                    end: usize,
                    _: i32,
                    mask: __m256| {
            // The packet's rays that entered this leaf.
            let entering = _mm256_and_ps(mask, rays_mask);
            // The leaf's entries start at a multiple of four (`flatten`): pack k / 4 holds
            // entries k..k + 4, triangles first, then spheres.
            for k in (first..end).step_by(4) {
                let pack = &scene.packs[k / 4];
                let mut tris = pack.triangles;
                while tris != 0 {
                    let tl = tris.trailing_zeros() as usize;
                    tris &= tris - 1;
                    let corner = |v: &[glam::Vec4; 3]| [v[0][tl], v[1][tl], v[2][tl]];
                    let h = triangle(p, corner(&pack.v0), corner(&pack.e1), corner(&pack.e2));
                    let candidate = _mm256_and_ps(h.hit, entering);
                    let prim = scene.prims[k + tl];
                    keep_nearer(best, t_limit, candidate, (h.t, h.b1, h.b2), prim);
                }
                let mut spheres = pack.spheres;
                while spheres != 0 {
                    let sl = spheres.trailing_zeros() as usize;
                    spheres &= spheres - 1;
                    let prim = scene.prims[k + sl];
                    let h = sphere(p, &scene.spheres[(prim & !PRIM_SPHERE_BIT) as usize]);
                    let candidate = _mm256_and_ps(h.hit, entering);
                    let zero = _mm256_setzero_ps();
                    keep_nearer(best, t_limit, candidate, (h.t, zero, zero), prim);
                }
            }
        };
        let single =
            |best: &mut Nearest, p: &mut Packet, t_limit: &mut __m256, node: u32, lanes: i32| {
                single_rays(scene, p, t_limit, best, node, lanes)
            };
        traverse::<true, LARGE, _>(scene, &mut p, &mut t_limit, &mut best, leaf, single);
        (
            lanes(t_limit),
            lanes(best.b1),
            lanes(best.b2),
            prims(best.prim),
        )
    }

    /// The lanes `bits` of the packet go on alone below wide node `node`, each from its nearest
    /// hit so far (`bvh::closest_below`): where few of a packet's rays enter a subtree, one
    /// ray's traversal tests a node's boxes in a quarter of the work of the packet's.
    #[inline]
    #[target_feature(enable = "avx")]
    fn single_rays(
        scene: &FlatScene,
        p: &Packet,
        t_limit: &mut __m256,
        best: &mut Nearest,
        node: u32,
        bits: i32,
    ) {
        let (mut t, mut b1, mut b2, mut prim) = (
            lanes(*t_limit),
            lanes(best.b1),
            lanes(best.b2),
            prims(best.prim),
        );
        let rows = rows(p);
        for l in lanes_of(bits as u32) {
            let ray = ray_at(&rows, l);
            let held = (prim[l] != NO_PRIM).then_some(Candidate {
                t: t[l],
                prim: prim[l],
                b1: b1[l],
                b2: b2[l],
            });
            if let Some(c) = closest_below(scene, &ray, node, t[l], held) {
                (t[l], b1[l], b2[l], prim[l]) = (c.t, c.b1, c.b2, c.prim);
            }
        }
        // SAFETY: eight f32 (or their bits) each.
        unsafe {
            *t_limit = _mm256_loadu_ps(t.as_ptr());
            best.b1 = _mm256_loadu_ps(b1.as_ptr());
            best.b2 = _mm256_loadu_ps(b2.as_ptr());
            best.prim = _mm256_loadu_ps(prim.as_ptr().cast());
        }
    }

    /// A primitive's hits (`hit` at `t` with error bound `t_err`) that lie within the segment,
    /// short of its end `t_limit` by their error bound, block those of the `entered` lanes still
    /// active: they are marked in `blocked` and stop.
    #[inline]
    #[target_feature(enable = "avx")]
    fn stop_blocked(
        p: &mut Packet,
        blocked: &mut i32,
        (hit, t, t_err): (__m256, __m256, __m256),
        t_limit: __m256,
        entered: i32,
    ) {
        let within = _mm256_and_ps(
            hit,
            _mm256_cmp_ps::<_CMP_LT_OS>(t, _mm256_sub_ps(t_limit, t_err)),
        );
        let now = _mm256_movemask_ps(within) & entered & p.active;
        *blocked |= now;
        p.active &= !now;
    }

    /// `occluded(ray, 1)` for up to eight rays: a lane stops at its first hit within the
    /// segment, short of the far end by the hit's error bound.
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[target_feature(enable = "avx")]
    pub unsafe fn occluded(scene: &FlatScene, rays: &[Ray], blocked: &mut [bool]) {
        let hit = occluded_in(scene, load(rays));
        for (l, b) in blocked.iter_mut().enumerate() {
            *b = hit & (1 << l) != 0;
        }
    }

    /// [`occluded`] for the lanes `lanes` of eight segments in rows: the blocked lanes' bits.
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[target_feature(enable = "avx")]
    pub unsafe fn occluded_lanes(scene: &FlatScene, (o, d): (&V8, &V8), lanes: u32) -> u32 {
        occluded_in(scene, from_lanes((o, d), lanes)) as u32
    }

    /// [`occluded_packet`] for the size of the scene's tree ([`LARGE_TREE_NODES`]).
    #[inline]
    #[target_feature(enable = "avx")]
    fn occluded_in(scene: &FlatScene, p: Packet) -> i32 {
        if scene.nodes.len() > LARGE_TREE_NODES {
            occluded_packet::<true>(scene, p)
        } else {
            occluded_packet::<false>(scene, p)
        }
    }

    /// The traversal of [`occluded`]: the blocked lanes' bits.
    #[inline]
    #[target_feature(enable = "avx")]
    fn occluded_packet<const LARGE: bool>(scene: &FlatScene, mut p: Packet) -> i32 {
        let mut t_limit = _mm256_set1_ps(1.0);
        let mut hit = 0i32;
        let leaf = |hit: &mut i32,
                    p: &mut Packet,
                    t_limit: &mut __m256,
                    first: usize,
                    end: usize,
                    entered: i32,
                    _: __m256| {
            for k in (first..end).step_by(4) {
                let pack = &scene.packs[k / 4];
                let mut tris = pack.triangles;
                while tris != 0 && p.active != 0 {
                    let tl = tris.trailing_zeros() as usize;
                    tris &= tris - 1;
                    let corner = |v: &[glam::Vec4; 3]| [v[0][tl], v[1][tl], v[2][tl]];
                    let h = triangle(p, corner(&pack.v0), corner(&pack.e1), corner(&pack.e2));
                    stop_blocked(p, hit, (h.hit, h.t, h.t_err), *t_limit, entered);
                }
                let mut spheres = pack.spheres;
                while spheres != 0 && p.active != 0 {
                    let sl = spheres.trailing_zeros() as usize;
                    spheres &= spheres - 1;
                    let prim = scene.prims[k + sl];
                    let h = sphere(p, &scene.spheres[(prim & !PRIM_SPHERE_BIT) as usize]);
                    stop_blocked(p, hit, (h.hit, h.t, h.t_err), *t_limit, entered);
                }
                if p.active == 0 {
                    return;
                }
            }
        };
        let single = |hit: &mut i32, p: &mut Packet, t_limit: &mut __m256, node: u32, bits: i32| {
            let (t, rows) = (lanes(*t_limit), rows(p));
            for l in lanes_of(bits as u32) {
                if occluded_below(scene, &ray_at(&rows, l), node, t[l]) {
                    *hit |= 1 << l;
                    p.active &= !(1 << l);
                }
            }
        };
        traverse::<false, LARGE, _>(scene, &mut p, &mut t_limit, &mut hit, leaf, single);
        hit
    }

    #[cfg(test)]
    mod lane_tests {
        use super::*;
        use crate::math::geometry::intersect_sphere;
        use glam::Vec3;

        /// Each lane of `sphere` is `intersect_sphere`, bit for bit: the same hit or miss, t
        /// and error bound, for rays from outside, inside and on the sphere, grazing ones, rays
        /// along the axes (zero components), and NaN and infinite directions.
        #[test]
        fn each_lane_of_the_sphere_test_is_the_scalar_test() {
            if !std::arch::is_x86_feature_detected!("avx") {
                return;
            }
            let spheres = [
                Sphere {
                    center: [0.5, -1.0, 2.0],
                    radius: 1.5,
                    ..Default::default()
                },
                Sphere {
                    center: [100.0, 3.0, -7.0],
                    radius: 0.01,
                    ..Default::default()
                },
                Sphere {
                    center: [0.0; 3],
                    radius: 1e4,
                    ..Default::default()
                },
            ];
            let mut rays = Vec::new();
            for i in 0..4000u32 {
                let u = |k: u32| {
                    crate::math::sampling::u32_to_unit_f32(
                        crate::math::sampling::pcg4d([i, k, 11, 12])[0],
                    )
                };
                let s = &spheres[(i % 3) as usize];
                let c = Vec3::from(s.center);
                let dir = Vec3::new(u(0) - 0.5, u(1) - 0.5, u(2) - 0.5);
                let on = c + dir.normalize() * s.radius;
                let o = match i % 5 {
                    0 => on,
                    1 => c + dir * s.radius,
                    2 => c + dir * s.radius * 8.0,
                    _ => c + Vec3::new(u(3) - 0.5, u(4) - 0.5, u(5) - 0.5) * s.radius * 4.0,
                };
                let mut d = match i % 7 {
                    0 => c - o,
                    1 => Vec3::new(u(6) - 0.5, 0.0, 0.0),
                    2 => Vec3::new(0.0, 0.0, -1.0),
                    3 => (c - o).cross(Vec3::new(u(7), u(8), 1.0)),
                    _ => Vec3::new(u(6) - 0.5, u(7) - 0.5, u(8) - 0.5),
                };
                if i % 97 == 0 {
                    d.y = f32::NAN;
                }
                if i % 89 == 0 {
                    d.x = f32::INFINITY;
                }
                rays.push((i % 3, Ray { o, d }));
            }
            let mut checked = [0u32; 2];
            for k in 0..3 {
                let these: Vec<Ray> = rays.iter().filter(|r| r.0 == k).map(|r| r.1).collect();
                for chunk in these.chunks(8) {
                    // SAFETY: the CPU has AVX (checked above).
                    let h = unsafe {
                        let p = load(chunk);
                        let h = sphere(&p, &spheres[k as usize]);
                        (_mm256_movemask_ps(h.hit), lanes(h.t), lanes(h.t_err))
                    };
                    for (l, ray) in chunk.iter().enumerate() {
                        let want = intersect_sphere(ray, &spheres[k as usize]);
                        assert_eq!(h.0 & (1 << l) != 0, want.is_some(), "ray {ray:?}");
                        if let Some(w) = want {
                            assert_eq!(h.1[l].to_bits(), w.t.to_bits(), "t of {ray:?}");
                            assert_eq!(h.2[l].to_bits(), w.t_err.to_bits(), "error of {ray:?}");
                        }
                        checked[usize::from(want.is_some())] += 1;
                    }
                }
            }
            // Both outcomes were met many times.
            assert!(checked[0] > 500 && checked[1] > 500, "{checked:?}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::{build_trees, Traversal};
    use crate::layout::{Sphere, Triangle};
    use glam::Vec3;

    /// A uniform number in [0, 1) for test data: number `k` of item `i` of stream `stream`.
    fn rnd(stream: u32, i: u32, k: u32) -> f32 {
        crate::math::sampling::u32_to_unit_f32(
            crate::math::sampling::pcg4d([i, k, stream, stream + 7])[0],
        )
    }

    /// 400 triangles in unit cubes over [0, 10)³, every tenth sharing an edge with the one
    /// before (so that rays through the edge meet two triangles at the same t), and spheres.
    fn scene(triangles: u32) -> FlatScene {
        let mut tris: Vec<Triangle> = Vec::new();
        for i in 0..triangles {
            let c = Vec3::new(rnd(1, i, 0), rnd(1, i, 1), rnd(1, i, 2)) * 10.0;
            let v = |k| (c + Vec3::new(rnd(1, i, k), rnd(1, i, k + 1), rnd(1, i, k + 2))).into();
            let t = if i % 10 == 1 {
                // The previous triangle's edge v1-v2 with a new third corner: a shared edge.
                let p = tris[i as usize - 1];
                Triangle::new(p.v2, p.v1, v(3), 0)
            } else {
                Triangle::new(v(3), v(6), v(9), 0)
            };
            tris.push(t);
        }
        let spheres = (0..6u32)
            .map(|i| Sphere {
                center: (Vec3::new(rnd(2, i, 0), rnd(2, i, 1), rnd(2, i, 2)) * 10.0).into(),
                radius: 0.3 + rnd(2, i, 3),
                ..Default::default()
            })
            .collect::<Vec<_>>();
        let (nodes, prims, wide) = build_trees(&tris, &spheres, Traversal::Cpu);
        FlatScene::from_tree(tris, spheres, nodes, prims, wide)
    }

    /// The shared edges the rays go through: triangles 10k and 10k + 1, k below this.
    fn pairs(scene: &FlatScene) -> u32 {
        (scene.triangles.len() as u32 / 10).min(40)
    }

    /// Rays of every kind a packet meets: from anywhere in the scene in any direction, along
    /// the axes (direction components exactly 0), through the midpoints of shared edges, and
    /// shadow segments between points of the scene.
    fn rays(scene: &FlatScene) -> Vec<Ray> {
        (0..3000u32)
            .map(|i| {
                let o = Vec3::new(rnd(3, i, 0), rnd(3, i, 1), rnd(3, i, 2)) * 12.0 - 1.0;
                let mut d = Vec3::new(rnd(3, i, 3), rnd(3, i, 4), rnd(3, i, 5)) - 0.5;
                match i % 5 {
                    0 => {
                        let axis = (i / 5 % 3) as usize;
                        d = Vec3::ZERO;
                        d[axis] = if rnd(3, i, 6) < 0.5 { -1.0 } else { 1.0 };
                    }
                    1 => {
                        // Through the middle of the edge triangles 10k and 10k + 1 share.
                        let t = scene.triangles[(i / 5 % pairs(scene) * 10) as usize];
                        let mid = (Vec3::from(t.v1) + Vec3::from(t.v2)) * 0.5;
                        d = mid - o;
                    }
                    2 => {
                        let b = Vec3::new(rnd(3, i, 7), rnd(3, i, 8), rnd(3, i, 9)) * 10.0;
                        d = b - o;
                    }
                    _ => {}
                }
                Ray { o, d }
            })
            .collect()
    }

    /// Packets find, ray for ray, what the scalar traversal finds: the same nearest hit (t,
    /// primitive and point, bit for bit; of two hits at the same t, both the lower primitive
    /// id) and the same answer for a shadow segment. The rays go in packets of every size from
    /// 1 to 8, so lanes past the rays are covered too. Of the rays through shared edges, those
    /// that meet both triangles at exactly the same t are counted: they must occur. Three trees:
    /// a small one (`LARGE_TREE_NODES`), a large one, and one over `PACKED_LEAVES_ABOVE`
    /// primitives of full leaves, deep enough that packets hand most rays on to single rays.
    #[test]
    fn packets_find_what_the_scalar_traversal_finds() {
        for triangles in [40, 400, 6000] {
            let scene = scene(triangles);
            let large = scene.nodes.len() > LARGE_TREE_NODES;
            assert_eq!(large, triangles > 40, "{} nodes", scene.nodes.len());
            packets_agree_with_the_scalar_traversal(&scene);
        }
    }

    fn packets_agree_with_the_scalar_traversal(scene: &FlatScene) {
        let rays = rays(scene);
        let mut ties = 0;
        let mut start = 0;
        let mut size = 1;
        while start < rays.len() {
            let chunk = &rays[start..(start + size).min(rays.len())];
            let mut hits = vec![None; chunk.len()];
            let mut blocked = vec![false; chunk.len()];
            intersect_closest_packets(scene, chunk, &mut hits);
            occluded_all(scene, chunk, &mut blocked);
            let n = scene.triangles.len();
            for (k, ray) in chunk.iter().enumerate() {
                let want = intersect_closest(scene, ray, f32::MAX);
                let key = |h: &Option<SurfaceHit>| h.map(|h| (h.t, h.prim, h.p, h.n));
                assert_eq!(
                    key(&hits[k]),
                    key(&want),
                    "{n} triangles, ray {}",
                    start + k
                );
                assert_eq!(
                    blocked[k],
                    occluded(scene, ray, 1.0),
                    "{n} triangles, ray {}",
                    start + k
                );
                if (start + k) % 5 == 1 {
                    let pair = (start + k) as u32 / 5 % pairs(scene) * 10;
                    let t = |i: u32| {
                        let tri = &scene.triangles[i as usize];
                        crate::math::geometry::intersect_triangle(ray, tri).map(|h| h.t)
                    };
                    if t(pair).is_some() && t(pair) == t(pair + 1) {
                        ties += 1;
                    }
                }
            }
            start += chunk.len();
            size = size % PACKET + 1;
        }
        // 29 with these fixed streams.
        assert!(
            ties >= 20,
            "{ties} rays met a shared edge's triangles at one t ({} triangles)",
            scene.triangles.len()
        );
    }

    /// Of two triangles a ray meets at the same t, the closest hit is the lower primitive id,
    /// in packets as in the scalar traversal, whichever order the tree holds them in.
    #[test]
    fn a_tie_in_t_goes_to_the_lower_primitive_id() {
        // Two triangles of the plane z = 1 sharing the edge x = 0, which the ray crosses at
        // (0, 0.25, 1), at t = 1 for both.
        let a = Triangle::new([0.0, -1.0, 1.0], [0.0, 1.0, 1.0], [-1.0, 0.0, 1.0], 0);
        let b = Triangle::new([0.0, 1.0, 1.0], [0.0, -1.0, 1.0], [1.0, 0.0, 1.0], 0);
        let ray = Ray {
            o: Vec3::new(-1.0, 0.25, 0.0),
            d: Vec3::new(1.0, 0.0, 1.0),
        };
        for t in [a, b] {
            let h = crate::math::geometry::intersect_triangle(&ray, &t).expect("both are hit");
            assert_eq!(h.t, 1.0);
        }
        for tris in [vec![a, b], vec![b, a]] {
            let (nodes, prims, wide) = build_trees(&tris, &[], Traversal::Cpu);
            let scene = FlatScene::from_tree(tris, vec![], nodes, prims, wide);
            let scalar = intersect_closest(&scene, &ray, f32::MAX).unwrap();
            let mut hits = [None; 3];
            intersect_closest_packets(&scene, &[ray; 3], &mut hits);
            let packet = hits[1].unwrap();
            assert_eq!(scalar.t, 1.0);
            assert_eq!(scalar.prim, 0, "scalar");
            assert_eq!(packet.prim, 0, "packet");
        }
    }

    /// A lane takes hits only from the leaves whose box it enters, as the scalar traversal:
    /// a ray in the plane of a box's face (direction component exactly 0) can miss the box by
    /// the slab test yet graze the triangle inside, and another lane entering that box must
    /// not hand it the hit, nor stop its shadow ray there.
    #[test]
    fn a_lane_takes_hits_only_from_the_boxes_it_enters() {
        // Triangle a spans x in [-1, 0]; c, far away, gives the tree a second leaf.
        let a = Triangle::new([0.0, -1.0, 1.0], [0.0, 1.0, 1.0], [-1.0, 0.0, 1.0], 0);
        let c = Triangle::new([5.0, 5.0, 5.0], [6.0, 5.0, 5.0], [5.0, 6.0, 5.0], 0);
        let (nodes, prims, wide) = build_trees(&[a, c], &[], Traversal::Cpu);
        let scene = FlatScene::from_tree(vec![a, c], vec![], nodes, prims, wide);
        // Lane 0 runs in the face x = 0 of a's box; lane 1 enters the box.
        let grazing = Ray {
            o: Vec3::new(0.0, 0.0, 0.0),
            d: Vec3::new(0.0, 0.0, 2.0),
        };
        let inside = Ray {
            o: Vec3::new(-0.25, 0.0, 0.0),
            d: Vec3::new(0.0, 0.0, 2.0),
        };
        let packet = [grazing, inside];
        let mut hits = [None; 2];
        let mut blocked = [false; 2];
        intersect_closest_packets(&scene, &packet, &mut hits);
        occluded_all(&scene, &packet, &mut blocked);
        for (k, ray) in packet.iter().enumerate() {
            let want = intersect_closest(&scene, ray, f32::MAX);
            assert_eq!(hits[k].map(|h| h.prim), want.map(|h| h.prim), "lane {k}");
            assert_eq!(blocked[k], occluded(&scene, ray, 1.0), "lane {k}");
        }
        assert!(hits[1].is_some() && blocked[1], "lane 1 hits a");
    }
}
