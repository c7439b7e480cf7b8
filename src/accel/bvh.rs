//! The bounding volume hierarchy: a binned-SAH build of a binary tree for the CPU's or the
//! shader's traversal ([`Traversal`]), collapsed into a four-wide tree of depth-first nodes that
//! hold their children's boxes ([`BvhNode`]), and the traversal of one ray (closest hit or any
//! hit) that the CPU's integrators use and `shaders/bvh.wgsl` repeats; the path tracer traces its
//! rays eight at a time instead where that pays ([`crate::accel::packet`], the same hits).

use crate::accel::wide_bvh::{intersect_wide, WIDTH};
use crate::layout::{
    BvhNode, FlatScene, Sphere, Triangle, TrianglePack, WideNode, EMPTY_SLOT, PRIM_PADDING,
    PRIM_SPHERE_BIT,
};
use crate::math::geometry::{
    intersect_sphere, intersect_triangles4, safe_inverse, sphere_point, triangle_hit_point,
    triangle_normal, Ray, Ray4, SurfaceHit, TriangleHits4,
};
use arrayvec::ArrayVec;
use glam::Vec3;

/// At most this many primitives in a leaf (pbrt-v4's `maxPrimsInNode` default is 255 for its
/// general BVH; small leaves suit a shader that visits one node per loop iteration).
pub const MAX_LEAF: usize = 4;
/// SAH buckets per axis.
const BINS: usize = 16;
/// Depth of the binary tree beyond which a node becomes a leaf whatever its size. The four-wide
/// tree is no deeper, and the traversal pushes at most three children per level, so its stack
/// never holds more than `3 * MAX_DEPTH` entries.
const MAX_DEPTH: usize = 60;
/// The most entries a traversal of the four-wide tree can push (three per level); the WGSL
/// stack is sized to the scene ([`stack_size`]), which this bounds.
pub const STACK_SIZE: usize = 3 * MAX_DEPTH;
/// The CPU's traversal stack over the wide tree: at most seven children pushed per level, and
/// the wide tree is no deeper than the four-wide one.
pub(crate) const WIDE_STACK_SIZE: usize = (crate::accel::wide_bvh::WIDTH - 1) * MAX_DEPTH;
/// A node visit's cost in the SAH relative to a leaf's test of one pack of four primitives
/// (pbrt-v4 uses 1/2 of one primitive's): the CPU's large trees.
const NODE_COST_PER_PACK: f32 = 0.5;
/// A node visit's cost relative to one primitive's test, in small trees, on both backends. 1
/// rather than 1/2 gives bunny_room larger leaves (853 four-wide nodes instead of 1 383) and
/// 1.04x the camera paths/s on the CPU, the rooms level; 2 cost tncg15_room 4 %
/// (docs/journal/2026-11-29_sah_collapse.md).
const NODE_COST_PER_PRIMITIVE: f32 = 1.0;
/// A node visit's cost relative to one primitive's test in the shader's large trees. On
/// lavapipe, bunny_room_1m, against the CPU's full leaves: path tracing 1.12 – 1.17x and vcm
/// level, with 152 k four-wide nodes; 1 gave path 1.15 – 1.18x but vcm 0.92 – 0.96x, with
/// 242 k nodes (docs/journal/2026-11-30_shader_leaves.md).
const SHADER_NODE_COST_PER_PRIMITIVE: f32 = 2.0;
/// Trees of more primitives than this are large, and costed for their traversal:
/// - The CPU's cost a leaf by its packs of four primitives, not by its primitives. In a large tree
///   the packets hand their rays to single-ray traversal below the top levels
///   ([`crate::accel::packet::SINGLE_RAY_LANES`]), which tests a leaf's four triangles at once
///   ([`intersect_triangles4`]): full leaves then halve the nodes and the memory of
///   bunny_room_1m and give it 1.15x the camera paths/s. In a small tree the rays stay in
///   packets, which test a leaf's triangles one at a time, and there the reference rooms lost
///   7 – 10 % with full leaves (docs/journal/2026-11-29_meshes.md).
/// - The shader's cost a leaf by its primitives, which it tests one per loop turn, and a node
///   visit as [`SHADER_NODE_COST_PER_PRIMITIVE`].
const LARGE_TREE_ABOVE: usize = 4096;

/// The traversal a tree is built for: the SAH costs a leaf and a node visit what that traversal
/// pays for them. Both backends read the same layout, and either renders any tree right.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Traversal {
    /// The CPU's (`accel::packet` and `traverse` over the eight-wide tree).
    Cpu,
    /// The shader's (`shaders/bvh.wgsl`, over the four-wide tree).
    Shader,
}

/// The SAH's costs of one tree.
#[derive(Clone, Copy)]
struct SahCosts {
    /// A leaf costs its packs of four, not its primitives.
    packs: bool,
    /// A node visit, in the leaf's unit.
    node: f32,
}

impl SahCosts {
    fn of(traversal: Traversal, primitives: usize) -> SahCosts {
        match (traversal, primitives > LARGE_TREE_ABOVE) {
            (_, false) => SahCosts {
                packs: false,
                node: NODE_COST_PER_PRIMITIVE,
            },
            (Traversal::Cpu, true) => SahCosts {
                packs: true,
                node: NODE_COST_PER_PACK,
            },
            (Traversal::Shader, true) => SahCosts {
                packs: false,
                node: SHADER_NODE_COST_PER_PRIMITIVE,
            },
        }
    }

    /// The cost of a leaf of `n` primitives.
    fn leaf(self, n: usize) -> f32 {
        if self.packs {
            n.div_ceil(4) as f32
        } else {
            n as f32
        }
    }
}

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

/// Builds the BVH over all triangles and spheres for `traversal`; returns the nodes (root first)
/// and the primitive references that leaves index into: every primitive once, each leaf starting
/// at a multiple of four, with [`PRIM_PADDING`] entries in the gaps and at the end (so `prims` is
/// not one entry per primitive).
pub fn build(
    triangles: &[Triangle],
    spheres: &[Sphere],
    traversal: Traversal,
) -> (Vec<BvhNode>, Vec<u32>) {
    let (nodes, prims, _) = build_trees(triangles, spheres, traversal);
    (nodes, prims)
}

/// [`build`], and the CPU's eight-wide tree collapsed from the same binary tree, with the same
/// leaves ([`collapse_wide`]).
pub fn build_trees(
    triangles: &[Triangle],
    spheres: &[Sphere],
    traversal: Traversal,
) -> (Vec<BvhNode>, Vec<u32>, Vec<WideNode>) {
    let Some((root, info)) = binary_tree(triangles, spheres, traversal) else {
        // Nothing to hit: a root whose slots are empty.
        let nodes = vec![BvhNode {
            count: [EMPTY_SLOT; 4],
            ..Default::default()
        }];
        let wide = crate::accel::wide_bvh::one_for_one(&nodes);
        return (nodes, Vec::new(), wide);
    };
    let mut starts = vec![0u32; info.len()];
    let four = Collapse::of(&root, 4);
    let (nodes, prims) = flatten_root(&root, &four, &info, &mut starts);
    // One programme's tables at a time: they take about as much memory as the binary tree.
    drop(four);
    (nodes, prims, collapse_wide(&root, &starts))
}

/// The binary SAH tree over the primitives, and their build-order records (None for none).
fn binary_tree(
    triangles: &[Triangle],
    spheres: &[Sphere],
    traversal: Traversal,
) -> Option<(Built, Vec<PrimInfo>)> {
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
    if info.is_empty() {
        return None;
    }
    let costs = SahCosts::of(traversal, info.len());
    let root = build_node(&mut info, 0, 0, costs);
    Some((root, info))
}

/// The CPU's eight-wide tree of the binary tree `root`, root first. The leaves are fixed (the
/// four-wide tree's: `starts` gives each leaf's first entry in `prims`, by its first primitive's
/// index in the build order), so the SAH cost of a collapse differs only in its nodes' boxes:
/// the choice of which binary nodes become eight-wide nodes minimises the sum of their surface
/// areas, each with at most eight slots (the dynamic programme of Ylitie, Karras and Laine
/// 2017, "Efficient incoherent ray traversal on GPUs through compressed wide BVHs", with its
/// leaves given). A greedy collapse (open the widest child until eight) leaves half-empty nodes
/// at the bottom of the tree.
fn collapse_wide(root: &Built, starts: &[u32]) -> Vec<WideNode> {
    let costs = Collapse::of(root, WIDTH);
    let mut wide = Vec::new();
    append_wide(root, &costs, starts, &mut wide);
    wide
}

/// Down to this depth of the binary tree, [`Collapse`] computes the two subtrees' tables in
/// parallel.
const PARALLEL_COLLAPSE_DEPTH: u32 = 6;

/// A binary node's collapse costs: `cost[i]` the least sum of node areas in its subtree when it
/// takes at most i slots of its parent (i = 1: it is a leaf or a node of its own), `choice[i]`
/// how (0: as with i − 1 slots; k: k slots to the left child, i − k to the right), and `own`
/// the left child's share of the slots of the node it becomes itself.
struct Collapse {
    cost: [f32; WIDTH + 1],
    choice: [u8; WIDTH + 1],
    own: u8,
    children: Option<Box<[Collapse; 2]>>,
}

impl Collapse {
    /// The costs of a collapse of `built` into nodes of at most `width` (≤ [`WIDTH`]) slots.
    fn of(built: &Built, width: usize) -> Collapse {
        Collapse::below(built, width, 0)
    }

    /// [`Collapse::of`] for a node at `depth`: the two subtrees in parallel near the root
    /// (the tables do not depend on the order).
    fn below(built: &Built, width: usize, depth: u32) -> Collapse {
        let Built::Interior { bounds, children } = built else {
            return Collapse {
                cost: [0.0; WIDTH + 1],
                choice: [0; WIDTH + 1],
                own: 0,
                children: None,
            };
        };
        let (l, r) = if depth < PARALLEL_COLLAPSE_DEPTH {
            rayon::join(
                || Collapse::below(&children[0], width, depth + 1),
                || Collapse::below(&children[1], width, depth + 1),
            )
        } else {
            (
                Collapse::below(&children[0], width, depth + 1),
                Collapse::below(&children[1], width, depth + 1),
            )
        };
        // split(j): the least cost of the two subtrees in j slots, and the left one's share.
        let split = |j: usize| {
            (1..j)
                .map(|k| (l.cost[k] + r.cost[j - k], k as u8))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .expect("j >= 2")
        };
        let (own_cost, own) = split(width);
        let mut cost = [f32::INFINITY; WIDTH + 1];
        let mut choice = [0; WIDTH + 1];
        cost[1] = bounds.area() + own_cost;
        for i in 2..=width {
            let (c, k) = split(i);
            (cost[i], choice[i]) = if c < cost[i - 1] {
                (c, k)
            } else {
                (cost[i - 1], 0)
            };
        }
        Collapse {
            cost,
            choice,
            own,
            children: Some(Box::new([l, r])),
        }
    }

    /// The slots that binary node `built` (with costs `self`) takes in `slots` of its parent,
    /// each with its costs.
    fn expand<'a>(&'a self, built: &'a Built, slots: usize, out: &mut Vec<(&'a Built, &'a Self)>) {
        let (Built::Interior { children, .. }, Some(c)) = (built, &self.children) else {
            out.push((built, self));
            return;
        };
        if slots <= 1 {
            out.push((built, self));
        } else if self.choice[slots] == 0 {
            self.expand(built, slots - 1, out);
        } else {
            let k = self.choice[slots] as usize;
            c[0].expand(&children[0], k, out);
            c[1].expand(&children[1], slots - k, out);
        }
    }

    /// The slots of the node that binary node `built` (with costs `self`, for nodes of `width`
    /// slots) becomes: its children's shares of the `width`, or itself where it is a leaf (a
    /// scene's root of up to `MAX_LEAF` primitives), each with its costs.
    fn slots<'a>(&'a self, built: &'a Built, width: usize) -> Vec<(&'a Built, &'a Self)> {
        let mut kids = Vec::with_capacity(width);
        match (built, &self.children) {
            (Built::Interior { children, .. }, Some(c)) => {
                let k = self.own as usize;
                c[0].expand(&children[0], k, &mut kids);
                c[1].expand(&children[1], width - k, &mut kids);
            }
            _ => kids.push((built, self)),
        }
        kids
    }
}

fn append_wide(built: &Built, costs: &Collapse, starts: &[u32], wide: &mut Vec<WideNode>) -> u32 {
    let kids = costs.slots(built, WIDTH);
    let at = wide.len();
    wide.push(WideNode::default());
    let mut node = WideNode::default();
    for (c, (kid, kid_costs)) in kids.iter().enumerate() {
        let (h, l) = (c / 4, c % 4);
        let b = kid.bounds();
        (node.min_x[h][l], node.min_y[h][l], node.min_z[h][l]) = (b.min.x, b.min.y, b.min.z);
        (node.max_x[h][l], node.max_y[h][l], node.max_z[h][l]) = (b.max.x, b.max.y, b.max.z);
        match kid {
            Built::Leaf { offset, count, .. } => {
                node.child[c] = starts[*offset as usize];
                node.count[c] = *count;
            }
            Built::Interior { .. } => {
                node.child[c] = append_wide(kid, kid_costs, starts, wide);
                node.count[c] = 0;
            }
        }
    }
    wide[at] = node;
    at as u32
}

/// The children of a `width`-wide node made from binary node `built` by the greedy collapse
/// (Wald et al. 2008, "Getting rid of packets"): its two children, and while fewer than
/// `width`, the interior one of largest surface area replaced by its two (the tests' yardstick
/// for [`Collapse`]).
#[cfg(test)]
fn open_widest(built: &Built, width: usize) -> Vec<&Built> {
    let mut kids: Vec<&Built> = match built {
        Built::Interior { children, .. } => children.iter().collect(),
        Built::Leaf { .. } => vec![built],
    };
    while kids.len() < width {
        let widest = kids
            .iter()
            .enumerate()
            .filter(|(_, k)| matches!(k, Built::Interior { .. }))
            .max_by(|(_, a), (_, b)| a.bounds().area().total_cmp(&b.bounds().area()))
            .map(|(i, _)| i);
        let Some(i) = widest else { break };
        let Built::Interior { children, .. } = kids.remove(i) else {
            unreachable!()
        };
        kids.extend(children.iter());
    }
    kids
}

/// Flattens the tree `root` into `nodes` and the padded `prims` that [`build`] returns.
fn flatten_root(
    root: &Built,
    costs: &Collapse,
    info: &[PrimInfo],
    starts: &mut [u32],
) -> (Vec<BvhNode>, Vec<u32>) {
    let mut nodes = Vec::with_capacity(info.len() / 4 + 1);
    let mut prims = Vec::with_capacity(info.len());
    flatten(root, costs, info, &mut nodes, &mut prims, starts);
    prims.resize(prims.len().next_multiple_of(4), PRIM_PADDING);
    (nodes, prims)
}

/// The CPU's copy of the leaves' triangles: pack k holds entries 4k..4k + 4 of `prims` (a leaf
/// starts at a multiple of four, so a pack never mixes two leaves), for
/// [`intersect_triangles4`].
pub fn triangle_packs(triangles: &[Triangle], prims: &[u32]) -> Vec<TrianglePack> {
    prims
        .chunks(4)
        .map(|entries| {
            let mut pack = TrianglePack::default();
            for (lane, &prim) in entries.iter().enumerate() {
                if prim == PRIM_PADDING {
                    continue;
                }
                if prim & PRIM_SPHERE_BIT != 0 {
                    pack.spheres |= 1 << lane;
                } else {
                    pack.set_triangle(lane, &triangles[prim as usize]);
                }
            }
            pack
        })
        .collect()
}

/// Appends the node `built` and its interior descendants in depth-first order as four-wide nodes;
/// returns its index. Which binary nodes become four-wide nodes is the collapse of least total
/// node area (`costs`, [`Collapse`]), which keeps the SAH tree's structure and about halves the
/// levels. A root that is a leaf (a scene of up to `MAX_LEAF` primitives the SAH does not split)
/// becomes a node of one slot.
///
/// Each leaf's primitives are appended to `prims` starting at a multiple of four (the gap filled
/// with [`PRIM_PADDING`], which no leaf covers), triangles before spheres: the CPU tests them
/// four at a time from [`triangle_packs`], and both backends visit them in this order.
fn flatten(
    built: &Built,
    costs: &Collapse,
    info: &[PrimInfo],
    nodes: &mut Vec<BvhNode>,
    prims: &mut Vec<u32>,
    starts: &mut [u32],
) -> u32 {
    let kids = costs.slots(built, 4);
    let index = nodes.len();
    nodes.push(BvhNode::default());
    let mut node = BvhNode {
        count: [EMPTY_SLOT; 4],
        ..Default::default()
    };
    for (c, (kid, kid_costs)) in kids.iter().enumerate() {
        let b = kid.bounds();
        (node.min_x[c], node.min_y[c], node.min_z[c]) = (b.min.x, b.min.y, b.min.z);
        (node.max_x[c], node.max_y[c], node.max_z[c]) = (b.max.x, b.max.y, b.max.z);
        match kid {
            Built::Leaf { offset, count, .. } => {
                debug_assert!(*count > 0, "an empty leaf would read as an interior node");
                prims.resize(prims.len().next_multiple_of(4), PRIM_PADDING);
                node.child[c] = prims.len() as u32;
                starts[*offset as usize] = prims.len() as u32;
                node.count[c] = *count;
                let leaf = &info[*offset as usize..(*offset + *count) as usize];
                let is_sphere = |p: &&PrimInfo| p.id & PRIM_SPHERE_BIT != 0;
                prims.extend(leaf.iter().filter(|p| !is_sphere(p)).map(|p| p.id));
                prims.extend(leaf.iter().filter(is_sphere).map(|p| p.id));
            }
            Built::Interior { .. } => {
                node.child[c] = flatten(kid, kid_costs, info, nodes, prims, starts);
                node.count[c] = 0;
            }
        }
    }
    nodes[index] = node;
    index as u32
}

/// Below this many primitives a subtree is built on the calling thread; above it the two
/// children are built in parallel (`rayon::join`). The tree is the same either way: each
/// subtree's build depends only on its own primitives.
const PARALLEL_BUILD: usize = 4096;

/// Builds the subtree over `info` (which starts at entry `start` of the whole array), reordering
/// `info` so that every leaf's primitives are contiguous, by the SAH's `costs`.
fn build_node(info: &mut [PrimInfo], start: usize, depth: usize, costs: SahCosts) -> Built {
    let leaf_cost = |n: usize| costs.leaf(n);
    let traversal = costs.node;
    let mut bounds = Aabb::EMPTY;
    let mut cbounds = Aabb::EMPTY;
    for p in info.iter() {
        bounds.grow(&p.bounds);
        cbounds.grow_point(p.centroid);
    }
    let count = info.len();
    let leaf = Built::Leaf {
        bounds,
        offset: start as u32,
        count: count as u32,
    };
    if count <= 1 || depth >= MAX_DEPTH {
        return leaf;
    }

    // Choose the split: the cheapest bucket boundary over all three axes by the surface area
    // heuristic, cost = C_trav + (C(N_l) A_l + C(N_r) A_r) / A (MacDonald and Booth 1990), C(N)
    // the cost of a leaf of N primitives.
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
        for p in info.iter() {
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
            right_cost[b] = leaf_cost(n) * acc.area();
        }
        let (mut acc, mut n) = (Aabb::EMPTY, 0usize);
        for b in 1..BINS {
            acc.grow(&boxes[b - 1]);
            n += counts[b - 1];
            if n == 0 || n == count {
                continue;
            }
            let cost = traversal + (leaf_cost(n) * acc.area() + right_cost[b]) / bounds.area();
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }

    let mid = match best {
        Some((cost, axis, boundary)) => {
            if count <= MAX_LEAF && cost >= leaf_cost(count) {
                return leaf;
            }
            let (lo, ext) = (cbounds.min[axis], extent[axis]);
            partition(info, |p| {
                let b = ((p.centroid[axis] - lo) / ext * BINS as f32) as usize;
                b.min(BINS - 1) < boundary
            })
        }
        None => {
            // All centroids coincide: no split separates anything, so halve by index.
            if count <= MAX_LEAF {
                return leaf;
            }
            count / 2
        }
    };
    let (left, right) = info.split_at_mut(mid);
    let (first, second) = if count > PARALLEL_BUILD {
        rayon::join(
            || build_node(left, start, depth + 1, costs),
            || build_node(right, start + mid, depth + 1, costs),
        )
    } else {
        (
            build_node(left, start, depth + 1, costs),
            build_node(right, start + mid, depth + 1, costs),
        )
    };
    Built::Interior {
        bounds,
        children: Box::new([first, second]),
    }
}

/// The number of nodes on the longest path from the root.
pub fn depth(nodes: &[BvhNode]) -> usize {
    fn walk(nodes: &[BvhNode], i: usize) -> usize {
        let n = &nodes[i];
        1 + (0..4)
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

/// A bound on the traversal stack: it holds children pushed by the ancestors of the node being
/// visited, at most three per node, so never more than three per level.
pub fn stack_size(nodes: &[BvhNode]) -> usize {
    3 * depth(nodes)
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

/// The primitive a traversal found nearest so far, before its surface point is computed
/// ([`surface_hit`]).
#[derive(Clone, Copy)]
pub(crate) struct Candidate {
    pub t: f32,
    pub prim: u32,
    pub b1: f32,
    pub b2: f32,
}

/// Closest-hit mode: the nearest intersection with `t` in (its error bound, `t_max`); of hits
/// at the same t (a ray through an edge two triangles share), the one of the lower primitive id
/// ([`nearer`]).
pub fn intersect_closest(scene: &FlatScene, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
    let c = closest_below(scene, ray, 0, t_max, None)?;
    Some(surface_hit(scene, ray, c))
}

/// The nearest hit of `ray` in the subtree of wide node `start`, if nearer than `best` (the
/// nearest found so far elsewhere, its t `t_limit` where there is one) by the rule of
/// [`nearer`]; else `best`. The packets of [`crate::accel::packet`] hand single rays to it deep
/// in a large tree.
#[inline]
pub(crate) fn closest_below(
    scene: &FlatScene,
    ray: &Ray,
    start: u32,
    t_limit: f32,
    mut best: Option<Candidate>,
) -> Option<Candidate> {
    traverse(
        scene,
        ray,
        start,
        t_limit,
        |prim, t, _t_err, b1, b2, t_limit| {
            if nearer(t, prim, *t_limit, best) {
                *t_limit = t;
                best = Some(Candidate { t, prim, b1, b2 });
            }
            false
        },
    );
    best
}

/// Whether a hit at `t` on primitive `prim` (its id as `prims` holds it: a triangle's index, or a
/// sphere's with the sphere bit) replaces `best`, the nearest so far (`t_limit` its t, or the ray's
/// end): nearer, or as near and of a lower id. The scalar traversal, the packets of
/// [`crate::accel::packet`] and `shaders/bvh.wgsl` visit nodes in different orders; with this rule
/// they keep the same primitive of two met at the same t. One case remains: once the first sets
/// `t_limit`, a leaf whose box's entry distance rounds above that t is skipped, so where the other
/// lies in such a leaf the order still decides.
#[inline]
pub(crate) fn nearer(t: f32, prim: u32, t_limit: f32, best: Option<Candidate>) -> bool {
    t < t_limit || (t == t_limit && best.is_some_and(|b| prim < b.prim))
}

/// Any-hit mode, for shadow rays: is anything within the open segment (0, `t_max`)? A hit within
/// its own error bound of `t_max` does not count, since the segment ends on a surface.
pub fn occluded(scene: &FlatScene, ray: &Ray, t_max: f32) -> bool {
    occluded_below(scene, ray, 0, t_max)
}

/// [`occluded`] within the subtree of wide node `start`.
#[inline]
pub(crate) fn occluded_below(scene: &FlatScene, ray: &Ray, start: u32, t_max: f32) -> bool {
    let mut hit = false;
    traverse(
        scene,
        ray,
        start,
        t_max,
        |_prim, t, t_err, _b1, _b2, t_limit| {
            if t < *t_limit - t_err {
                hit = true;
            }
            hit
        },
    );
    #[cfg(feature = "counters")]
    counters::last_was_shadow();
    hit
}

/// Nearest first: offers child `entry` (a node and its distance) of the node being visited.
/// The nearest child offered so far becomes `next`, the node visited next; the others go onto
/// `stack` above `base` (its height before this node's offers) in decreasing distance, so that
/// the nearest of them pops first. The ray traversal and the clearance query share it.
#[inline(always)]
pub(crate) fn offer_nearest_first<const N: usize>(
    entry: (u32, f32),
    next: &mut Option<(u32, f32)>,
    stack: &mut ArrayVec<(u32, f32), N>,
    base: usize,
) {
    let entry = match *next {
        None => {
            *next = Some(entry);
            return;
        }
        Some(n) if entry.1 < n.1 => {
            *next = Some(entry);
            n
        }
        Some(_) => entry,
    };
    let mut j = stack.len();
    stack.push(entry);
    while j > base && stack[j - 1].1 < stack[j].1 {
        stack.swap(j - 1, j);
        j -= 1;
    }
}

/// One traversal for both modes, over the CPU's wide tree (`FlatScene::wide`, the four-wide tree
/// collapsed to eight-wide nodes: 4 – 13 % more camera paths/s than the four-wide tree it is
/// made of, docs/journal/2026-11-25_wide_nodes.md). At each node the children's boxes are tested at
/// once. The leaves among the hit children are tested first, so that their hits lower t_limit
/// before anything is pushed; then the nearest hit interior child is visited next and the others
/// are pushed with their entry distances, in decreasing distance, so that the nearest of them pops
/// first: a missed child is never pushed and a pushed one that a closer hit has since passed is
/// dropped when popped. The order is `shaders/bvh.wgsl`'s, where it gave lavapipe 1.2 – 1.4x;
/// here it measured level with pushes in slot order (docs/journal/2026-11-29_meshes.md). A leaf's
/// triangles are tested four at a time ([`intersect_triangles4`], bit for
/// bit the scalar test per lane; 15 – 18 % less render time than one at a time) and their hits
/// reported in entry order, so the result is the scalar traversal's. Both measured in
/// docs/journal/2026-11-23_cpu_traversal.md. `on_hit(prim, t, t_err, b1, b2, &mut t_limit)` decides
/// what a hit means; it returns true to stop at once (any-hit). The traversal starts at wide node
/// `start` (0, the root, but for a packet's ray going on alone below a node).
#[inline]
fn traverse(
    scene: &FlatScene,
    ray: &Ray,
    start: u32,
    t_max: f32,
    mut on_hit: impl FnMut(u32, f32, f32, f32, f32, &mut f32) -> bool,
) {
    let inv_d = safe_inverse(ray.d);
    let ray4 = Ray4::new(ray);
    let mut t_limit = t_max;
    #[cfg(feature = "counters")]
    let _work = counters::Ray::start();
    // Interior children still to visit, with the distance at which the ray enters them.
    let mut stack = ArrayVec::<(u32, f32), WIDE_STACK_SIZE>::new();
    let mut current = start;
    loop {
        let node = &scene.wide[current as usize];
        #[cfg(feature = "counters")]
        counters::node();
        let (t_enter, entered) = intersect_wide(node, ray.o, inv_d, t_limit);
        // Bit c set: the ray enters child c's box (a leaf's in `leaves`, a node's in `inner`).
        let mut interior = 0u32;
        for (c, &count) in node.count.iter().enumerate() {
            interior |= u32::from(count == 0) << c;
        }
        let (mut leaves, mut inner) = (entered & !interior, entered & interior);
        while leaves != 0 {
            let c = leaves.trailing_zeros() as usize;
            leaves &= leaves - 1;
            // A box that a hit in another leaf has since passed.
            if t_enter[c] > t_limit {
                continue;
            }
            // The leaf's entries of `prims` start at a multiple of four (`flatten`), so pack
            // k / 4 holds entries k..k + 4: its triangles are tested at once, in lane (= entry)
            // order, then its spheres, which follow a leaf's triangles.
            let (first, end) = (
                node.child[c] as usize,
                (node.child[c] + node.count[c]) as usize,
            );
            debug_assert!(first % 4 == 0, "a leaf starts at a multiple of four");
            #[cfg(feature = "counters")]
            counters::primitives(node.count[c]);
            for k in (first..end).step_by(4) {
                let pack = &scene.packs[k / 4];
                let hits = if pack.triangles != 0 {
                    intersect_triangles4(&ray4, pack)
                } else {
                    TriangleHits4::MISS
                };
                let mut lanes = hits.mask;
                while lanes != 0 {
                    let l = lanes.trailing_zeros() as usize;
                    lanes &= lanes - 1;
                    let prim = scene.prims[k + l];
                    if on_hit(
                        prim,
                        hits.t[l],
                        hits.t_err[l],
                        hits.b1[l],
                        hits.b2[l],
                        &mut t_limit,
                    ) {
                        return;
                    }
                }
                let mut lanes = pack.spheres;
                while lanes != 0 {
                    let l = lanes.trailing_zeros() as usize;
                    lanes &= lanes - 1;
                    let prim = scene.prims[k + l];
                    let s = &scene.spheres[(prim & !PRIM_SPHERE_BIT) as usize];
                    if let Some(h) = intersect_sphere(ray, s) {
                        if on_hit(prim, h.t, h.t_err, 0.0, 0.0, &mut t_limit) {
                            return;
                        }
                    }
                }
            }
        }
        let mut next: Option<(u32, f32)> = None;
        let base = stack.len();
        while inner != 0 {
            let c = inner.trailing_zeros() as usize;
            inner &= inner - 1;
            if t_enter[c] > t_limit {
                continue;
            }
            offer_nearest_first((node.child[c], t_enter[c]), &mut next, &mut stack, base);
        }
        // Descend into the nearest interior child, or pop the most recently pushed one that the
        // ray still enters before t_limit.
        while next.is_none() {
            match stack.pop() {
                Some((n, t)) if t <= t_limit => next = Some((n, t)),
                Some(_) => {}
                None => return,
            }
        }
        current = next.map_or(0, |(n, _)| n);
    }
}

/// Work counters of the traversal (feature `counters`, for `examples/lane_occupancy.rs`): per
/// ray traced on this thread, the nodes visited and the primitives tested, the units of work
/// that `shaders/bvh.wgsl`'s loops take one at a time (the CPU tests a leaf's triangles four at
/// a time, but counts them one by one here, as the shader takes them).
#[cfg(feature = "counters")]
pub mod counters {
    use std::cell::{Cell, RefCell};

    /// One ray's work.
    #[derive(Clone, Copy, Debug, Default)]
    pub struct Work {
        pub nodes: u32,
        pub primitives: u32,
        /// An any-hit (shadow) ray rather than a closest-hit one.
        pub shadow: bool,
    }

    thread_local! {
        static CURRENT: Cell<Work> = const { Cell::new(Work {
            nodes: 0,
            primitives: 0,
            shadow: false,
        }) };
        static LOG: RefCell<Vec<Work>> = const { RefCell::new(Vec::new()) };
    }

    /// Counts one ray from its creation to its drop, when its work goes to the log.
    pub(super) struct Ray;
    impl Ray {
        pub(super) fn start() -> Ray {
            CURRENT.with(|c| c.set(Work::default()));
            Ray
        }
    }
    impl Drop for Ray {
        fn drop(&mut self) {
            let w = CURRENT.with(|c| c.get());
            LOG.with(|l| l.borrow_mut().push(w));
        }
    }
    pub(super) fn node() {
        CURRENT.with(|c| {
            c.set(Work {
                nodes: c.get().nodes + 1,
                ..c.get()
            })
        });
    }
    pub(super) fn primitives(n: u32) {
        CURRENT.with(|c| {
            let w = c.get();
            c.set(Work {
                primitives: w.primitives + n,
                ..w
            })
        });
    }
    pub(super) fn last_was_shadow() {
        LOG.with(|l| {
            if let Some(w) = l.borrow_mut().last_mut() {
                w.shadow = true;
            }
        });
    }
    /// The work of the rays traced on this thread since the last call, in the order traced.
    pub fn take() -> Vec<Work> {
        LOG.with(|l| std::mem::take(&mut *l.borrow_mut()))
    }
}

pub(crate) fn surface_hit(scene: &FlatScene, ray: &Ray, c: Candidate) -> SurfaceHit {
    if c.prim & PRIM_SPHERE_BIT == 0 {
        let tri = &scene.triangles[c.prim as usize];
        let (p, p_err) = triangle_hit_point(tri, c.b1, c.b2);
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
    use crate::math::geometry::intersect_triangle;

    fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
        Triangle::new(a, b, c, 0)
    }

    /// A uniform number in [0, 1) for test data: number `k` of item `i` of stream `stream`.
    fn rnd(stream: u32, i: u32, k: u32) -> f32 {
        crate::math::sampling::u32_to_unit_f32(
            crate::math::sampling::pcg4d([i, k, stream, stream + 1])[0],
        )
    }

    /// `n` triangles of stream `stream`, each within a unit cube (moved by `shift`) of a centre
    /// uniform in [0, spread)³.
    fn triangle_soup(n: u32, stream: u32, spread: f32, shift: f32) -> Vec<Triangle> {
        (0..n)
            .map(|i| {
                let c = Vec3::new(rnd(stream, i, 0), rnd(stream, i, 1), rnd(stream, i, 2)) * spread;
                let v = |k| {
                    (c + Vec3::new(
                        rnd(stream, i, k),
                        rnd(stream, i, k + 1),
                        rnd(stream, i, k + 2),
                    ) + shift)
                        .into()
                };
                tri(v(3), v(6), v(9))
            })
            .collect()
    }

    /// `stack_size` bounds the traversal stack: checked against the largest stack the
    /// traversal's pushes reach over every node of a tree of 500 triangles.
    #[test]
    fn stack_size_bounds_the_traversal_stack() {
        let tris = triangle_soup(500, 3, 20.0, 0.0);
        let (nodes, _) = build(&tris, &[], Traversal::Cpu);
        let bound = stack_size(&nodes);
        // Replay the traversal's pushes with every box hit (the worst case): each node pushes
        // all its interior children but one.
        let mut worst = 0;
        let mut stack = vec![];
        let mut current = 0usize;
        let mut visits = 0;
        loop {
            visits += 1;
            let node = &nodes[current];
            let mut next = None;
            for c in 0..4 {
                if node.count[c] == 0 {
                    if let Some(n) = next.replace(node.child[c] as usize) {
                        stack.push(n);
                        worst = worst.max(stack.len());
                    }
                }
            }
            match next.or_else(|| stack.pop()) {
                Some(n) => current = n,
                None => break,
            }
        }
        assert_eq!(visits, nodes.len(), "every node is visited once");
        assert!(worst <= bound, "stack reached {worst}, bound {bound}");
        assert!(bound <= STACK_SIZE);
    }

    /// The leaves' mean number of primitives.
    fn mean_leaf(nodes: &[BvhNode]) -> f64 {
        let sizes: Vec<u32> = nodes
            .iter()
            .flat_map(|n| n.count)
            .filter(|&k| k != 0 && k != EMPTY_SLOT)
            .collect();
        sizes.iter().sum::<u32>() as f64 / sizes.len() as f64
    }

    /// Up to [`LARGE_TREE_ABOVE`] primitives both traversals get the same tree; above it the
    /// CPU's leaves fill their packs of four and the shader's, costed by primitive, split further.
    #[test]
    fn only_large_trees_differ_by_traversal() {
        let small = triangle_soup(LARGE_TREE_ABOVE as u32, 7, 20.0, 0.0);
        let (cpu, cpu_prims) = build(&small, &[], Traversal::Cpu);
        let (gpu, gpu_prims) = build(&small, &[], Traversal::Shader);
        assert_eq!(
            bytemuck::cast_slice::<_, u8>(&cpu),
            bytemuck::cast_slice::<_, u8>(&gpu)
        );
        assert_eq!(cpu_prims, gpu_prims);

        let large = triangle_soup(LARGE_TREE_ABOVE as u32 + 1, 7, 20.0, 0.0);
        let cpu = mean_leaf(&build(&large, &[], Traversal::Cpu).0);
        let gpu = mean_leaf(&build(&large, &[], Traversal::Shader).0);
        eprintln!("mean primitives a leaf: {cpu:.2} (packs), {gpu:.2} (primitives)");
        assert!(cpu > 1.25 * gpu, "{cpu:.2} vs {gpu:.2}");
    }

    /// Every primitive is in exactly one leaf, and every child box contains its primitives.
    #[test]
    fn leaves_partition_the_primitives_inside_their_boxes() {
        let tris = triangle_soup(300, 5, 10.0, 0.0);
        let (nodes, prims) = build(&tris, &[], Traversal::Cpu);
        let mut seen = vec![0; tris.len()];
        for n in &nodes {
            for c in 0..4 {
                if n.count[c] == 0 || n.count[c] == EMPTY_SLOT {
                    continue;
                }
                let (lo, hi) = n.child_bounds(c);
                for k in n.child[c]..n.child[c] + n.count[c] {
                    let t = &tris[prims[k as usize] as usize];
                    seen[prims[k as usize] as usize] += 1;
                    for v in [t.v0, t.v1, t.v2] {
                        let v = Vec3::from(v);
                        assert!(v.cmpge(lo).all() && v.cmple(hi).all());
                    }
                }
            }
        }
        assert!(seen.iter().all(|&k| k == 1));
    }

    /// Brute force over every primitive: the nearest hit's t, and whether anything blocks the
    /// segment (0, t_max) the way `occluded` decides it (a hit within its error bound of t_max
    /// does not count).
    fn brute_force(tris: &[Triangle], spheres: &[Sphere], ray: &Ray, t_max: f32) -> (f32, bool) {
        let mut hits: Vec<(f32, f32)> = tris
            .iter()
            .filter_map(|t| intersect_triangle(ray, t).map(|h| (h.t, h.t_err)))
            .collect();
        hits.extend(
            spheres
                .iter()
                .filter_map(|s| intersect_sphere(ray, s).map(|h| (h.t, h.t_err))),
        );
        let nearest = hits.iter().map(|h| h.0).fold(f32::INFINITY, f32::min);
        (nearest, hits.iter().any(|&(t, e)| t < t_max - e))
    }

    fn scene_of(tris: Vec<Triangle>, spheres: Vec<Sphere>) -> FlatScene {
        let (nodes, prims, wide) = build_trees(&tris, &spheres, Traversal::Cpu);
        FlatScene::from_tree(tris, spheres, nodes, prims, wide)
    }

    /// The total surface area of the nodes of a collapse of `built` that opens nodes greedily
    /// ([`open_widest`]) into nodes of `width` slots.
    fn greedy_area(built: &Built, width: usize) -> f32 {
        let Built::Interior { bounds, .. } = built else {
            return 0.0;
        };
        bounds.area()
            + open_widest(built, width)
                .into_iter()
                .map(|k| greedy_area(k, width))
                .sum::<f32>()
    }

    /// The collapse of the binary tree into four- and eight-wide nodes has the least total node
    /// area that any choice of nodes reaches with the leaves given: at most the greedy
    /// collapse's, and here less. The wide tree built has that area.
    #[test]
    fn the_wide_trees_are_the_collapses_of_least_node_area() {
        let tris = triangle_soup(3000, 7, 10.0, 0.0);
        let (root, _) = binary_tree(&tris, &[], Traversal::Cpu).unwrap();
        for width in [4, 8] {
            let least = Collapse::of(&root, width).cost[1];
            let greedy = greedy_area(&root, width);
            eprintln!("width {width}: least {least}, greedy {greedy}");
            assert!(
                least < 0.99 * greedy,
                "width {width}: {least} against {greedy}"
            );
        }
        let (nodes, _, wide) = build_trees(&tris, &[], Traversal::Cpu);
        let union = |boxes: Vec<(Vec3, Vec3)>| {
            let mut b = Aabb::EMPTY;
            for (lo, hi) in boxes {
                b.grow(&Aabb { min: lo, max: hi });
            }
            b.area()
        };
        let wide_area: f32 = wide
            .iter()
            .map(|n| {
                union(
                    (0..WIDTH)
                        .filter(|&c| n.count[c] != EMPTY_SLOT)
                        .map(|c| n.child_bounds(c))
                        .collect(),
                )
            })
            .sum();
        let four_area: f32 = nodes
            .iter()
            .map(|n| {
                union(
                    (0..4)
                        .filter(|&c| n.count[c] != EMPTY_SLOT)
                        .map(|c| n.child_bounds(c))
                        .collect(),
                )
            })
            .sum();
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * b;
        assert!(
            close(wide_area, Collapse::of(&root, 8).cost[1]),
            "{wide_area}"
        );
        assert!(
            close(four_area, Collapse::of(&root, 4).cost[1]),
            "{four_area}"
        );
    }

    /// The scene's nearest hit along `ray` and whether it blocks the segment (0, 1) are what
    /// testing every primitive of `tris` and `spheres` gives.
    fn assert_ray_agrees(
        scene: &FlatScene,
        tris: &[Triangle],
        spheres: &[Sphere],
        ray: &Ray,
        what: &str,
    ) {
        let (nearest, _) = brute_force(tris, spheres, ray, f32::INFINITY);
        let got = intersect_closest(scene, ray, f32::INFINITY).map_or(f32::INFINITY, |h| h.t);
        assert_eq!(got, nearest, "{what}");
        assert_eq!(
            occluded(scene, ray, 1.0),
            brute_force(tris, spheres, ray, 1.0).1,
            "{what}"
        );
    }

    /// The BVH must find exactly what testing every primitive finds: the nearest hit, and for
    /// shadow segments of every length whether anything blocks them.
    #[test]
    fn bvh_agrees_with_brute_force() {
        let rnd = |i, k| rnd(1, i, k);
        let tris = triangle_soup(300, 1, 10.0, -0.5);
        let spheres = vec![Sphere {
            center: [5.0, 5.0, 5.0],
            radius: 1.0,
            ..Default::default()
        }];
        let scene = scene_of(tris.clone(), spheres.clone());
        for i in 0..2000u32 {
            let o = Vec3::new(rnd(i, 20), rnd(i, 21), rnd(i, 22)) * 10.0;
            let mut d = Vec3::new(rnd(i, 23), rnd(i, 24), rnd(i, 25)) - 0.5;
            // Every fourth ray along an axis (two direction components exactly 0).
            if i % 4 == 0 {
                let axis = (i / 4 % 3) as usize;
                let mut a = Vec3::ZERO;
                a[axis] = if d[axis] < 0.0 { -1.0 } else { 1.0 };
                d = a;
            }
            let ray = Ray { o, d };
            let got = intersect_closest(&scene, &ray, f32::INFINITY).map_or(f32::INFINITY, |h| h.t);
            assert_eq!(
                got,
                brute_force(&tris, &spheres, &ray, f32::INFINITY).0,
                "ray {i}"
            );
            // Shadow segments ending before, at and after the nearest hit.
            for t_max in [0.5 * got, got, 2.0 * got, 1.0, 3.0] {
                if !t_max.is_finite() {
                    continue;
                }
                assert_eq!(
                    occluded(&scene, &ray, t_max),
                    brute_force(&tris, &spheres, &ray, t_max).1,
                    "ray {i}, t_max {t_max}"
                );
            }
        }
    }

    /// A leaf larger than four primitives (the depth limit makes them), triangles and spheres
    /// mixed, spans several packs: the traversal tests all of it, the spheres after the
    /// triangles, and finds what testing every primitive finds.
    #[test]
    fn a_leaf_of_many_packs_agrees_with_brute_force() {
        let rnd = |i, k| rnd(9, i, k);
        let tris = triangle_soup(11, 9, 4.0, -0.5);
        let spheres: Vec<Sphere> = (0..3u32)
            .map(|i| Sphere {
                center: [rnd(i, 30) * 4.0, rnd(i, 31) * 4.0, rnd(i, 32) * 4.0],
                radius: 0.5,
                ..Default::default()
            })
            .collect();
        let info: Vec<PrimInfo> = (0..14u32)
            .map(|i| PrimInfo {
                bounds: Aabb {
                    min: Vec3::splat(-2.0),
                    max: Vec3::splat(6.0),
                },
                centroid: Vec3::ZERO,
                // Spheres first in the builder's order, so the flattening must move them.
                id: if i < 3 { i | PRIM_SPHERE_BIT } else { i - 3 },
            })
            .collect();
        let leaf = Built::Leaf {
            bounds: info[0].bounds,
            offset: 0,
            count: 14,
        };
        let (nodes, prims) = flatten_root(&leaf, &Collapse::of(&leaf, 4), &info, &mut [0; 14]);
        assert_eq!((nodes[0].child[0], nodes[0].count[0]), (0, 14));
        assert!(prims[11..14].iter().all(|p| p & PRIM_SPHERE_BIT != 0));
        let wide = crate::accel::wide_bvh::one_for_one(&nodes);
        let scene = FlatScene::from_tree(tris.clone(), spheres.clone(), nodes, prims, wide);
        for i in 0..2000u32 {
            let o = Vec3::new(rnd(i, 20), rnd(i, 21), rnd(i, 22)) * 4.0;
            let d = Vec3::new(rnd(i, 23), rnd(i, 24), rnd(i, 25)) - 0.5;
            assert_ray_agrees(&scene, &tris, &spheres, &Ray { o, d }, &format!("ray {i}"));
        }
    }

    /// Scenes of one to four primitives (whose root the SAH may leave a leaf) and an empty one.
    #[test]
    fn small_scenes_agree_with_brute_force() {
        let rnd = |i, k| rnd(7, i, k);
        for n in 0..=4u32 {
            let tris: Vec<Triangle> = (0..n)
                .map(|i| {
                    let v = |k| (Vec3::new(rnd(i, k), rnd(i, k + 1), rnd(i, k + 2)) * 2.0).into();
                    tri(v(0), v(3), v(6))
                })
                .collect();
            let scene = scene_of(tris.clone(), vec![]);
            for i in 0..500u32 {
                let o = Vec3::new(rnd(i, 20), rnd(i, 21), rnd(i, 22)) * 2.0 - 0.5;
                let d = Vec3::new(rnd(i, 23), rnd(i, 24), rnd(i, 25)) - 0.5;
                let what = format!("{n} triangles, ray {i}");
                assert_ray_agrees(&scene, &tris, &[], &Ray { o, d }, &what);
            }
        }
    }
}
