//! The clearance of a surface point: how far the merge disk about it can reach before it meets
//! another surface (`merging::local_radius`).
//!
//! A merge at a camera vertex x counts the photons within r of x as if they lay on a disk of
//! area π r² in x's tangent plane. Where another surface comes within r (a wall meeting the
//! floor, an emitter hung below the ceiling, a box standing on the floor), that is false: part
//! of the disk lies behind the other surface, where no light arrives, and photons on the other
//! surface are counted in its place. So merges darken the edges of a room and the outlines of
//! what stands in it, by far the largest share of merging's bias in the reference rooms. The
//! clearance is the distance from x to the nearest primitive that is not in x's own plane
//! (for a point on a sphere: to every other primitive); a disk of that radius lies wholly on
//! x's plane in front of everything else. (A plane that ends in the open, with nothing beyond
//! its edge, is not seen: no reference scene has one.)

use crate::accel::bvh::{offer_nearest_first, STACK_SIZE};
use crate::layout::{FlatScene, Triangle, EMPTY_SLOT, PRIM_PADDING, PRIM_SPHERE_BIT};
use arrayvec::ArrayVec;
use glam::Vec3;

/// Two triangles lie in one plane when their unit normals agree to within this (|n₁ · n₂|
/// above 1 − this) ...
pub const COPLANAR_COS: f32 = 1e-5;

/// ... and the other's vertices lie off the plane by at most this share of the coordinates'
/// magnitude (the point's largest coordinate plus the bound, at least 1).
pub const COPLANAR_OFFSET: f32 = 1e-5;

/// The distance from `p`, a point on primitive `prim` (an id as `FlatScene::prims` holds it), to
/// the nearest primitive not in the plane of `prim` (a triangle) or other than `prim` (a
/// sphere), or `bound` where none lies nearer than `bound`.
pub fn clearance(scene: &FlatScene, p: Vec3, prim: u32, bound: f32) -> f32 {
    if scene.nodes.is_empty() {
        return bound;
    }
    let own = (prim & PRIM_SPHERE_BIT == 0).then(|| &scene.triangles[prim as usize]);
    let tolerance = COPLANAR_OFFSET * (p.abs().max_element() + bound).max(1.0);
    let mut best2 = bound * bound;
    // Interior nodes still to visit, each with its box's squared distance from p. At each node
    // the leaves in reach are tested first; then the traversal goes on into the nearest interior
    // child in reach and pushes the others farthest first, so that the nearest of them pops
    // first (at most three per level, `bvh::stack_size`), and a popped node that best2 has since
    // passed is dropped. Nearest first, the primitives that lower best2 are met soonest and fewer
    // boxes stay in reach; the minimum found is the same in any order.
    let mut stack = ArrayVec::<(u32, f32), STACK_SIZE>::new();
    let mut current = 0u32;
    loop {
        let node = &scene.nodes[current as usize];
        // Squared distance from p to each child's box.
        let d2: [f32; 4] = std::array::from_fn(|c| {
            let (lo, hi) = node.child_bounds(c);
            (lo - p).max(p - hi).max(Vec3::ZERO).length_squared()
        });
        for (c, &d2_box) in d2.iter().enumerate() {
            let count = node.count[c];
            if count == EMPTY_SLOT || count == 0 || d2_box >= best2 {
                continue;
            }
            for k in node.child[c]..node.child[c] + count {
                let other = scene.prims[k as usize];
                if other == PRIM_PADDING || other == prim {
                    continue;
                }
                let d2_other = if other & PRIM_SPHERE_BIT != 0 {
                    let s = &scene.spheres[(other & !PRIM_SPHERE_BIT) as usize];
                    let d = (p - Vec3::from(s.center)).length() - s.radius;
                    d * d
                } else {
                    let t = &scene.triangles[other as usize];
                    if own.is_some_and(|o| coplanar(o, t, tolerance)) {
                        continue;
                    }
                    (closest_point_on_triangle(p, t) - p).length_squared()
                };
                best2 = best2.min(d2_other);
            }
        }
        let mut next: Option<(u32, f32)> = None;
        let base = stack.len();
        for (c, &d2_box) in d2.iter().enumerate() {
            if node.count[c] != 0 || d2_box >= best2 {
                continue;
            }
            offer_nearest_first((node.child[c], d2_box), &mut next, &mut stack, base);
        }
        // Descend into the nearest interior child, or pop the most recently pushed one still in
        // reach.
        while next.is_none() {
            match stack.pop() {
                Some(entry) if entry.1 < best2 => next = Some(entry),
                Some(_) => {}
                None => break,
            }
        }
        match next {
            Some((n, _)) => current = n,
            None => break,
        }
    }
    // Where nothing lies nearer, the bound itself: a GPU's square root, which WGSL lets be
    // approximate, may round sqrt(bound²) off it (shaders/clearance.wgsl, the same step).
    if best2 >= bound * bound {
        bound
    } else {
        best2.sqrt()
    }
}

/// Whether triangle `t` lies in the plane of `own`.
pub fn coplanar(own: &Triangle, t: &Triangle, tolerance: f32) -> bool {
    let n = Vec3::from(own.n);
    let v0 = Vec3::from(own.v0);
    n.dot(Vec3::from(t.n)).abs() > 1.0 - COPLANAR_COS
        && [t.v0, t.v1, t.v2]
            .iter()
            .all(|v| n.dot(Vec3::from(*v) - v0).abs() <= tolerance)
}

/// The point of triangle `t` nearest to `p` (Ericson, "Real-Time Collision Detection", 5.1.5:
/// the Voronoi region of a vertex, an edge or the face).
pub fn closest_point_on_triangle(p: Vec3, t: &Triangle) -> Vec3 {
    let (a, b, c) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}
