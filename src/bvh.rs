//! The bounding volume hierarchy: a binned-SAH build into depth-first flat nodes, and the one
//! traversal (closest hit or any hit) that the CPU integrator uses and `shaders/bvh.wgsl` repeats.

use crate::flat::{BvhNode, FlatScene, Sphere, Triangle, PRIM_SPHERE_BIT};
use crate::geometry::{
    intersect_aabb, intersect_sphere, intersect_triangle, safe_inverse, sphere_point,
    triangle_normal, triangle_point, Ray, SurfaceHit,
};
use glam::Vec3;

/// At most this many primitives in a leaf (pbrt-v4's `maxPrimsInNode` default is 255 for its
/// general BVH; small leaves suit a shader that visits one node per loop iteration).
pub const MAX_LEAF: usize = 4;
/// SAH buckets per axis.
const BINS: usize = 16;
/// Depth beyond which a node becomes a leaf whatever its size; the traversal stack holds
/// `STACK_SIZE` entries and a depth-first traversal pushes at most one per level.
const MAX_DEPTH: usize = 60;
/// Entries in the traversal stack (shared with the WGSL private array).
pub const STACK_SIZE: usize = 64;
/// Cost of visiting a node relative to one primitive test (pbrt-v4 uses 1/2).
const TRAVERSAL_COST: f32 = 0.5;

#[derive(Clone, Copy)]
struct Aabb {
    min: Vec3,
    max: Vec3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };
    fn grow(&mut self, o: &Aabb) {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
    }
    fn grow_point(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    fn area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }
    fn centroid(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }
}

struct PrimInfo {
    bounds: Aabb,
    centroid: Vec3,
    id: u32,
}

/// Builds the BVH over all triangles and spheres; returns the nodes (root first) and the
/// primitive references that leaves index into.
pub fn build(triangles: &[Triangle], spheres: &[Sphere]) -> (Vec<BvhNode>, Vec<u32>) {
    let mut info: Vec<PrimInfo> = Vec::with_capacity(triangles.len() + spheres.len());
    for (i, t) in triangles.iter().enumerate() {
        let mut b = Aabb::EMPTY;
        for v in [t.v0, t.v1, t.v2] {
            b.grow_point(Vec3::from(v));
        }
        info.push(PrimInfo {
            bounds: b,
            centroid: b.centroid(),
            id: i as u32,
        });
    }
    for (i, s) in spheres.iter().enumerate() {
        let c = Vec3::from(s.center);
        // Widen by one ulp-scale step so rounding of c +- r never cuts the sphere.
        let r = Vec3::splat(s.radius) + c.abs() * f32::EPSILON;
        let b = Aabb {
            min: c - r - Vec3::splat(s.radius * f32::EPSILON),
            max: c + r + Vec3::splat(s.radius * f32::EPSILON),
        };
        info.push(PrimInfo {
            bounds: b,
            centroid: c,
            id: i as u32 | PRIM_SPHERE_BIT,
        });
    }
    let mut nodes = Vec::with_capacity(2 * info.len());
    let n = info.len();
    build_node(&mut info, 0, n, 0, &mut nodes);
    let prims = info.iter().map(|p| p.id).collect();
    (nodes, prims)
}

/// Appends the subtree over `info[start..end]` in depth-first order and returns its index.
fn build_node(
    info: &mut [PrimInfo],
    start: usize,
    end: usize,
    depth: usize,
    nodes: &mut Vec<BvhNode>,
) -> usize {
    let index = nodes.len();
    nodes.push(BvhNode::default());
    let mut bounds = Aabb::EMPTY;
    let mut cbounds = Aabb::EMPTY;
    for p in &info[start..end] {
        bounds.grow(&p.bounds);
        cbounds.grow_point(p.centroid);
    }
    let count = end - start;
    let make_leaf = |nodes: &mut Vec<BvhNode>| {
        nodes[index] = BvhNode {
            min: bounds.min.into(),
            offset: start as u32,
            max: bounds.max.into(),
            count_axis: count as u32,
        };
        index
    };
    if count <= 1 || depth >= MAX_DEPTH && count <= 0xffff {
        return make_leaf(nodes);
    }

    // Choose the split: the cheapest bucket boundary over all three axes by the surface area
    // heuristic, cost = C_trav + (N_l A_l + N_r A_r) / A (MacDonald and Booth 1990).
    let extent = cbounds.max - cbounds.min;
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bucket boundary)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let bucket_of = |c: Vec3| {
            let b = ((c[axis] - cbounds.min[axis]) / extent[axis] * BINS as f32) as usize;
            b.min(BINS - 1)
        };
        let mut counts = [0usize; BINS];
        let mut boxes = [Aabb::EMPTY; BINS];
        for p in &info[start..end] {
            let b = bucket_of(p.centroid);
            counts[b] += 1;
            boxes[b].grow(&p.bounds);
        }
        // Sweep from the right to get the cost of each boundary's right side, then from the left.
        let mut right_cost = [0.0f32; BINS];
        let (mut acc, mut n) = (Aabb::EMPTY, 0usize);
        for b in (1..BINS).rev() {
            acc.grow(&boxes[b]);
            n += counts[b];
            right_cost[b] = n as f32 * acc.area();
        }
        let (mut acc, mut n) = (Aabb::EMPTY, 0usize);
        for b in 1..BINS {
            acc.grow(&boxes[b - 1]);
            n += counts[b - 1];
            if n == 0 || n == count {
                continue;
            }
            let cost = TRAVERSAL_COST + (n as f32 * acc.area() + right_cost[b]) / bounds.area();
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }

    let (axis, mid) = match best {
        Some((cost, axis, boundary)) => {
            if count <= MAX_LEAF && cost >= count as f32 {
                return make_leaf(nodes);
            }
            let (lo, ext) = (cbounds.min[axis], extent[axis]);
            let mid = partition(&mut info[start..end], |p| {
                let b = ((p.centroid[axis] - lo) / ext * BINS as f32) as usize;
                b.min(BINS - 1) < boundary
            });
            (axis, start + mid)
        }
        None => {
            // All centroids coincide: no split separates anything, so halve by index.
            if count <= MAX_LEAF {
                return make_leaf(nodes);
            }
            (0, start + count / 2)
        }
    };
    build_node(info, start, mid, depth + 1, nodes);
    let second = build_node(info, mid, end, depth + 1, nodes);
    nodes[index] = BvhNode {
        min: bounds.min.into(),
        offset: second as u32,
        max: bounds.max.into(),
        count_axis: (axis as u32) << 16,
    };
    index
}

/// The number of interior nodes on the longest root-to-leaf path: the most entries a
/// near-first traversal ever holds on its stack.
pub fn depth(nodes: &[BvhNode]) -> usize {
    fn walk(nodes: &[BvhNode], i: usize) -> usize {
        let n = &nodes[i];
        if n.count() > 0 {
            0
        } else {
            1 + walk(nodes, i + 1).max(walk(nodes, n.offset as usize))
        }
    }
    if nodes.is_empty() {
        0
    } else {
        walk(nodes, 0)
    }
}

/// In-place partition; returns the number of elements for which `pred` holds (moved first).
fn partition(v: &mut [PrimInfo], pred: impl Fn(&PrimInfo) -> bool) -> usize {
    let mut i = 0;
    for j in 0..v.len() {
        if pred(&v[j]) {
            v.swap(i, j);
            i += 1;
        }
    }
    i
}

/// The primitive a traversal found nearest so far.
#[derive(Clone, Copy)]
struct Candidate {
    t: f32,
    prim: u32,
    b1: f32,
    b2: f32,
}

/// Closest-hit mode: the nearest intersection with `t` in (its error bound, `t_max`).
pub fn intersect_closest(scene: &FlatScene, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
    let mut best: Option<Candidate> = None;
    traverse(scene, ray, t_max, |prim, t, _t_err, b1, b2, t_limit| {
        if t < *t_limit {
            *t_limit = t;
            best = Some(Candidate { t, prim, b1, b2 });
        }
        false
    });
    let c = best?;
    Some(surface_hit(scene, ray, c))
}

/// Any-hit mode, for shadow rays: is anything within the open segment (0, `t_max`)? A hit within
/// its own error bound of `t_max` does not count, since the segment ends on a surface.
pub fn occluded(scene: &FlatScene, ray: &Ray, t_max: f32) -> bool {
    let mut hit = false;
    traverse(scene, ray, t_max, |_prim, t, t_err, _b1, _b2, t_limit| {
        if t < *t_limit - t_err {
            hit = true;
        }
        hit
    });
    hit
}

/// One traversal for both modes: near child first (by the sign of the ray direction on the
/// node's split axis), an explicit stack, and `on_hit(prim, t, t_err, b1, b2, &mut t_limit)`
/// deciding what a hit means; it returns true to stop at once (any-hit).
#[inline]
fn traverse(
    scene: &FlatScene,
    ray: &Ray,
    t_max: f32,
    mut on_hit: impl FnMut(u32, f32, f32, f32, f32, &mut f32) -> bool,
) {
    let inv_d = safe_inverse(ray.d);
    let dir_is_neg = [inv_d.x < 0.0, inv_d.y < 0.0, inv_d.z < 0.0];
    let mut t_limit = t_max;
    let mut stack = [0u32; STACK_SIZE];
    let mut sp = 0usize;
    let mut current = 0u32;
    loop {
        let node = &scene.nodes[current as usize];
        if intersect_aabb(
            Vec3::from(node.min),
            Vec3::from(node.max),
            ray.o,
            inv_d,
            t_limit,
        ) {
            let count = node.count();
            if count > 0 {
                for k in node.offset..node.offset + count {
                    let prim = scene.prims[k as usize];
                    let stop = if prim & PRIM_SPHERE_BIT == 0 {
                        match intersect_triangle(ray, &scene.triangles[prim as usize]) {
                            Some(h) => on_hit(prim, h.t, h.t_err, h.b1, h.b2, &mut t_limit),
                            None => false,
                        }
                    } else {
                        let s = &scene.spheres[(prim & !PRIM_SPHERE_BIT) as usize];
                        match intersect_sphere(ray, s) {
                            Some(h) => on_hit(prim, h.t, h.t_err, 0.0, 0.0, &mut t_limit),
                            None => false,
                        }
                    };
                    if stop {
                        return;
                    }
                }
            } else {
                // Visit the near child first; remember the far one.
                if dir_is_neg[node.axis()] {
                    stack[sp] = current + 1;
                    current = node.offset;
                } else {
                    stack[sp] = node.offset;
                    current += 1;
                }
                sp += 1;
                continue;
            }
        }
        if sp == 0 {
            return;
        }
        sp -= 1;
        current = stack[sp];
    }
}

fn surface_hit(scene: &FlatScene, ray: &Ray, c: Candidate) -> SurfaceHit {
    if c.prim & PRIM_SPHERE_BIT == 0 {
        let tri = &scene.triangles[c.prim as usize];
        let (p, p_err) = triangle_point(tri, c.b1, c.b2);
        SurfaceHit {
            t: c.t,
            p,
            p_err,
            n: triangle_normal(tri),
            material: tri.material,
            prim: c.prim,
        }
    } else {
        let s = &scene.spheres[(c.prim & !PRIM_SPHERE_BIT) as usize];
        let (p, p_err, n) = sphere_point(ray, s, c.t);
        SurfaceHit {
            t: c.t,
            p,
            p_err,
            n,
            material: s.material,
            prim: c.prim,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
        Triangle {
            v0: a,
            v1: b,
            v2: c,
            ..Default::default()
        }
    }

    /// `depth` is the traversal stack's high-water mark: checked against the largest stack a
    /// near-first traversal actually reaches over many rays.
    #[test]
    fn depth_bounds_the_traversal_stack() {
        use crate::sampling::pcg4d;
        let rnd = |i: u32, k: u32| crate::sampling::u32_to_unit_f32(pcg4d([i, k, 3, 4])[0]);
        let tris: Vec<Triangle> = (0..500u32)
            .map(|i| {
                let c = Vec3::new(rnd(i, 0), rnd(i, 1), rnd(i, 2)) * 20.0;
                let v = |k| (c + Vec3::new(rnd(i, k), rnd(i, k + 1), rnd(i, k + 2))).into();
                tri(v(3), v(6), v(9))
            })
            .collect();
        let (nodes, _) = build(&tris, &[]);
        let depth = depth(&nodes);
        // Replay the traversal order of `traverse` with every box hit: the worst case.
        let mut worst = 0;
        for signs in 0..8u32 {
            let mut stack = vec![];
            let mut current = 0usize;
            loop {
                let node = &nodes[current];
                if node.count() == 0 {
                    let neg = signs >> node.axis() & 1 == 1;
                    let (near, far) = if neg {
                        (node.offset as usize, current + 1)
                    } else {
                        (current + 1, node.offset as usize)
                    };
                    stack.push(far);
                    worst = worst.max(stack.len());
                    current = near;
                    continue;
                }
                match stack.pop() {
                    Some(n) => current = n,
                    None => break,
                }
            }
        }
        assert!(worst <= depth, "stack reached {worst}, depth {depth}");
        assert!(
            worst >= depth - 2,
            "depth {depth} is a loose bound ({worst})"
        );
        assert!(depth < STACK_SIZE);
    }

    /// The BVH must find exactly what testing every primitive finds.
    #[test]
    fn bvh_agrees_with_brute_force() {
        use crate::sampling::pcg4d;
        let rnd = |i: u32, k: u32| crate::sampling::u32_to_unit_f32(pcg4d([i, k, 1, 2])[0]);
        let mut tris = Vec::new();
        for i in 0..300u32 {
            let c = Vec3::new(rnd(i, 0), rnd(i, 1), rnd(i, 2)) * 10.0;
            let v = |k| c + Vec3::new(rnd(i, k), rnd(i, k + 1), rnd(i, k + 2)) - 0.5;
            tris.push(tri(v(3).into(), v(6).into(), v(9).into()));
        }
        let spheres = vec![Sphere {
            center: [5.0, 5.0, 5.0],
            radius: 1.0,
            ..Default::default()
        }];
        let (nodes, prims) = build(&tris, &spheres);
        let scene = FlatScene {
            triangles: tris.clone(),
            spheres: spheres.clone(),
            nodes,
            prims,
            ..Default::default()
        };
        for i in 0..2000u32 {
            let o = Vec3::new(rnd(i, 20), rnd(i, 21), rnd(i, 22)) * 10.0;
            let d = Vec3::new(rnd(i, 23), rnd(i, 24), rnd(i, 25)) - 0.5;
            let ray = Ray { o, d };
            let mut brute = f32::INFINITY;
            for t in &tris {
                if let Some(h) = intersect_triangle(&ray, t) {
                    brute = brute.min(h.t);
                }
            }
            if let Some(h) = intersect_sphere(&ray, &spheres[0]) {
                brute = brute.min(h.t);
            }
            let got = intersect_closest(&scene, &ray, f32::INFINITY).map_or(f32::INFINITY, |h| h.t);
            assert_eq!(got, brute, "ray {i}");
            assert_eq!(
                occluded(&scene, &ray, f32::INFINITY),
                brute.is_finite(),
                "ray {i}"
            );
        }
    }
}
