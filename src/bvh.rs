//! The bounding volume hierarchy: a binned-SAH build of a binary tree, flattened into depth-first
//! nodes that each hold both children's boxes ([`BvhNode`]), and the one traversal (closest hit
//! or any hit) that the CPU integrator uses and `shaders/bvh.wgsl` repeats.

use crate::flat::{BvhNode, FlatScene, Sphere, Triangle, PRIM_SPHERE_BIT};
use crate::geometry::{
    intersect_aabb_pair, intersect_sphere, intersect_triangle, safe_inverse, sphere_point,
    triangle_normal, triangle_point, Ray, SurfaceHit,
};
use glam::Vec3;

/// At most this many primitives in a leaf (pbrt-v4's `maxPrimsInNode` default is 255 for its
/// general BVH; small leaves suit a shader that visits one node per loop iteration).
pub const MAX_LEAF: usize = 4;
/// SAH buckets per axis.
const BINS: usize = 16;
/// Depth beyond which a node becomes a leaf whatever its size; the traversal stack holds
/// `STACK_SIZE` entries and the traversal pushes at most one per level.
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

/// A node of the binary tree as the builder makes it, before flattening.
enum Built {
    Leaf {
        bounds: Aabb,
        offset: u32,
        count: u32,
    },
    Interior {
        bounds: Aabb,
        children: Box<[Built; 2]>,
    },
}

impl Built {
    fn bounds(&self) -> &Aabb {
        match self {
            Built::Leaf { bounds, .. } | Built::Interior { bounds, .. } => bounds,
        }
    }
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
    let n = info.len();
    let root = build_node(&mut info, 0, n, 0);
    // The root must be an interior node; a scene of one primitive gets a root whose two
    // children are the same leaf.
    let root = match root {
        leaf @ Built::Leaf { .. } => {
            let (bounds, offset, count) = match &leaf {
                Built::Leaf {
                    bounds,
                    offset,
                    count,
                } => (*bounds, *offset, *count),
                Built::Interior { .. } => unreachable!(),
            };
            let twin = Built::Leaf {
                bounds,
                offset,
                count,
            };
            Built::Interior {
                bounds,
                children: Box::new([leaf, twin]),
            }
        }
        interior => interior,
    };
    let mut nodes = Vec::with_capacity(n);
    flatten(&root, &mut nodes);
    let prims = info.iter().map(|p| p.id).collect();
    (nodes, prims)
}

/// Appends the interior node `built` and its interior descendants in depth-first order, each
/// holding its children's boxes; returns its index.
fn flatten(built: &Built, nodes: &mut Vec<BvhNode>) -> u32 {
    let Built::Interior { children, .. } = built else {
        unreachable!("leaves live in their parent's node");
    };
    let index = nodes.len();
    nodes.push(BvhNode::default());
    let mut node = BvhNode::default();
    for (c, child) in children.iter().enumerate() {
        let b = child.bounds();
        for (row, axis) in [(&mut node.x, 0), (&mut node.y, 1), (&mut node.z, 2)] {
            row[c] = b.min[axis];
            row[2 + c] = b.max[axis];
        }
        match child {
            Built::Leaf { offset, count, .. } => {
                node.child[c] = *offset;
                node.count[c] = *count;
            }
            Built::Interior { .. } => {
                node.child[c] = flatten(child, nodes);
                node.count[c] = 0;
            }
        }
    }
    nodes[index] = node;
    index as u32
}

/// Builds the subtree over `info[start..end]`, reordering `info` so that every leaf's
/// primitives are contiguous.
fn build_node(info: &mut [PrimInfo], start: usize, end: usize, depth: usize) -> Built {
    let mut bounds = Aabb::EMPTY;
    let mut cbounds = Aabb::EMPTY;
    for p in &info[start..end] {
        bounds.grow(&p.bounds);
        cbounds.grow_point(p.centroid);
    }
    let count = end - start;
    let leaf = Built::Leaf {
        bounds,
        offset: start as u32,
        count: count as u32,
    };
    if count <= 1 || depth >= MAX_DEPTH {
        return leaf;
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

    let mid = match best {
        Some((cost, axis, boundary)) => {
            if count <= MAX_LEAF && cost >= count as f32 {
                return leaf;
            }
            let (lo, ext) = (cbounds.min[axis], extent[axis]);
            let mid = partition(&mut info[start..end], |p| {
                let b = ((p.centroid[axis] - lo) / ext * BINS as f32) as usize;
                b.min(BINS - 1) < boundary
            });
            start + mid
        }
        None => {
            // All centroids coincide: no split separates anything, so halve by index.
            if count <= MAX_LEAF {
                return leaf;
            }
            start + count / 2
        }
    };
    let first = build_node(info, start, mid, depth + 1);
    let second = build_node(info, mid, end, depth + 1);
    Built::Interior {
        bounds,
        children: Box::new([first, second]),
    }
}

/// The number of nodes on the longest path from the root: the traversal pushes at most one
/// child per node it visits, so its stack never holds more entries than this.
pub fn depth(nodes: &[BvhNode]) -> usize {
    fn walk(nodes: &[BvhNode], i: usize) -> usize {
        let n = &nodes[i];
        1 + (0..2)
            .filter(|&c| n.count[c] == 0)
            .map(|c| walk(nodes, n.child[c] as usize))
            .max()
            .unwrap_or(0)
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

/// One traversal for both modes. At each node both children's boxes are tested at once; the
/// hit children are taken nearer first (by entry distance): a leaf's primitives are tested at
/// once, the first interior child is visited next and a second one is pushed with its entry
/// distance, so a child the ray misses is never pushed and a pushed one that a closer hit has
/// since passed is dropped when popped. `on_hit(prim, t, t_err, b1, b2, &mut t_limit)` decides
/// what a hit means; it returns true to stop at once (any-hit).
#[inline]
fn traverse(
    scene: &FlatScene,
    ray: &Ray,
    t_max: f32,
    mut on_hit: impl FnMut(u32, f32, f32, f32, f32, &mut f32) -> bool,
) {
    let inv_d = safe_inverse(ray.d);
    let mut t_limit = t_max;
    // Interior children still to visit, with the distance at which the ray enters them.
    let mut stack = [(0u32, 0.0f32); STACK_SIZE];
    let mut sp = 0usize;
    let mut current = 0u32;
    loop {
        let node = &scene.nodes[current as usize];
        let t_enter = intersect_aabb_pair(node, ray.o, inv_d, t_limit);
        let near = usize::from(t_enter[1] < t_enter[0]);
        let mut next = None;
        for c in [near, 1 - near] {
            // A missed box, or one that a hit in the nearer child's leaf has since passed.
            if t_enter[c] < 0.0 || t_enter[c] > t_limit {
                continue;
            }
            let count = node.count[c];
            if count == 0 {
                if next.is_none() {
                    next = Some(node.child[c]);
                } else {
                    stack[sp] = (node.child[c], t_enter[c]);
                    sp += 1;
                }
                continue;
            }
            for k in node.child[c]..node.child[c] + count {
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
        }
        // Descend into the first interior child, or pop the most recently pushed one that the
        // ray still enters before t_limit.
        if next.is_none() {
            while sp > 0 {
                sp -= 1;
                if stack[sp].1 <= t_limit {
                    next = Some(stack[sp].0);
                    break;
                }
            }
        }
        match next {
            Some(n) => current = n,
            None => return,
        }
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
        // Replay the traversal of `traverse` with every box hit (the worst case), taking
        // either child as the nearer one by a pattern of bits.
        let mut worst = 0;
        for pattern in 0..8u32 {
            let mut stack = vec![];
            let mut current = 0usize;
            let mut visits = 0u32;
            loop {
                let node = &nodes[current];
                visits += 1;
                let near = ((pattern >> (visits % 3)) & 1) as usize;
                let mut next = None;
                for c in [near, 1 - near] {
                    if node.count[c] == 0 {
                        if next.is_none() {
                            next = Some(node.child[c] as usize);
                        } else {
                            stack.push(node.child[c] as usize);
                            worst = worst.max(stack.len());
                        }
                    }
                }
                if let Some(n) = next {
                    current = n;
                    continue;
                }
                match stack.pop() {
                    Some(n) => current = n,
                    None => break,
                }
            }
            assert_eq!(visits as usize, nodes.len(), "every node is visited once");
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
