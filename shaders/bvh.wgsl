// The BVH traversal: `src/accel/bvh.rs`, one traversal with a closest-hit and an any-hit mode: the four
// children's boxes tested at once, the interior children nearest first, an explicit stack in a
// private array.

// Specialised by the host to `bvh::stack_size`: the traversal pushes at most three nodes per
// level.
const STACK_SIZE: u32 = 64u;

// "No interior child to visit next" (`None` in src/accel/bvh.rs).
const NO_NODE: u32 = 0xffffffffu;

// Entry k of the primitive references (packed four to a vec4<u32>).
fn prim_ref(k: u32) -> u32 {
    return prims[k >> 2u][k & 3u];
}

// Nearest first (`bvh::offer_nearest_first`): offers child `entry` (a node and the bits of its
// distance) of the node being visited. The nearest child offered so far becomes `next` (.x
// NO_NODE for none), the node visited next; the others go onto `stack` above `base` (its height
// before this node's offers) in decreasing distance, so that the nearest of them pops first. The
// ray traversal and the clearance query share it.
fn offer_nearest_first(
    entry_in: vec2<u32>,
    next: ptr<function, vec2<u32>>,
    stack: ptr<function, array<vec2<u32>, STACK_SIZE>>,
    base: u32,
    sp: ptr<function, u32>,
) {
    var entry = entry_in;
    if (*next).x == NO_NODE {
        *next = entry;
        return;
    }
    if bitcast<f32>(entry.y) < bitcast<f32>((*next).y) {
        let held = *next;
        *next = entry;
        entry = held;
    }
    var j = *sp;
    (*stack)[j] = entry;
    *sp = j + 1u;
    while j > base && bitcast<f32>((*stack)[j - 1u].y) < bitcast<f32>((*stack)[j].y) {
        let held = (*stack)[j - 1u];
        (*stack)[j - 1u] = (*stack)[j];
        (*stack)[j] = held;
        j -= 1u;
    }
}

// The primitive a traversal found nearest so far.
struct Candidate {
    found: bool,
    t: f32,
    prim: u32,
    b1: f32,
    b2: f32,
}

// Closest-hit mode (any_hit = false): the nearest intersection with t in (its error bound,
// t_max); of hits at the same t, the one of the lower primitive id (`bvh::nearer`). Any-hit
// mode (any_hit = true), for shadow rays: stops at the first hit within the open segment
// (0, t_max), not counting hits within their own error bound of t_max.
//
// At each node the four children's boxes are tested at once. The leaves among the hit children
// are tested first, so that their hits lower best.t before anything is pushed; then the nearest
// hit interior child is visited next and the others are pushed with their entry distances (bits
// in .y), in decreasing distance, so that the nearest of them pops first: a missed child is never
// pushed and a pushed one that a closer hit has since passed is dropped when popped. On lavapipe
// the sorted pushes gave 1.2 - 1.4x the camera paths/s of pushes in slot order on every scene; on
// the CPU they measured level (docs/journal/2026-11-29_meshes.md). The nearest hit is the same
// either way (`bvh::nearer`).
fn traverse(ray: Ray, t_max: f32, any_hit: bool) -> Candidate {
    var best = Candidate(false, t_max, 0u, 0.0, 0.0);
    let inv_d = safe_inverse(ray.d);
    var stack: array<vec2<u32>, STACK_SIZE>;
    var sp = 0u;
    var current = 0u;
    loop {
        let node = nodes[current];
        let t_enter = intersect_aabb4(node, ray.o, inv_d, best.t);
        // Bit c set: the ray enters child c's box (a leaf's in `leaves`, a node's in `inner`).
        var leaves = 0u;
        var inner = 0u;
        for (var c = 0u; c < 4u; c++) {
            let hit = select(0u, 1u << c, t_enter[c] >= 0.0);
            if node.count[c] == 0u {
                inner |= hit;
            } else {
                leaves |= hit;
            }
        }
        while leaves != 0u {
            let c = countTrailingZeros(leaves);
            leaves &= leaves - 1u;
            // A box that a hit in another leaf has since passed.
            if t_enter[c] > best.t {
                continue;
            }
            // The CPU tests a leaf's triangles four at a time in SIMD lanes (`TrianglePack`,
            // the same arithmetic per lane), then its spheres; here one entry per iteration, in
            // the same order (a leaf's triangles come before its spheres in `prims`).
            for (var k = node.child[c]; k < node.child[c] + node.count[c]; k++) {
                let prim = prim_ref(k);
                var t = 0.0;
                var t_err = 0.0;
                var b1 = 0.0;
                var b2 = 0.0;
                var found = false;
                if (prim & PRIM_SPHERE_BIT) == 0u {
                    let h = intersect_triangle(ray, triangles[prim]);
                    found = h.found;
                    t = h.t;
                    t_err = h.t_err;
                    b1 = h.b1;
                    b2 = h.b2;
                } else {
                    let h = intersect_sphere(ray, spheres[prim & ~PRIM_SPHERE_BIT]);
                    found = h.found;
                    t = h.t;
                    t_err = h.t_err;
                }
                if found {
                    if any_hit {
                        if t < best.t - t_err {
                            best.found = true;
                            return best;
                        }
                    } else if t < best.t || (t == best.t && best.found && prim < best.prim) {
                        best = Candidate(true, t, prim, b1, b2);
                    }
                }
            }
        }
        var next = vec2<u32>(NO_NODE, 0u);
        let base = sp;
        while inner != 0u {
            let c = countTrailingZeros(inner);
            inner &= inner - 1u;
            if t_enter[c] > best.t {
                continue;
            }
            let entry = vec2<u32>(node.child[c], bitcast<u32>(t_enter[c]));
            offer_nearest_first(entry, &next, &stack, base, &sp);
        }
        // Descend into the nearest interior child, or pop the most recently pushed one that the
        // ray still enters before best.t.
        while next.x == NO_NODE && sp > 0u {
            sp -= 1u;
            if bitcast<f32>(stack[sp].y) <= best.t {
                next = stack[sp];
            }
        }
        if next.x == NO_NODE {
            break;
        }
        current = next.x;
    }
    return best;
}

// The closest hit as a surface: point, error bound, normal, material.
fn surface_hit(ray: Ray, c: Candidate) -> SurfaceHit {
    if (c.prim & PRIM_SPHERE_BIT) == 0u {
        let tri = triangles[c.prim];
        let pe = triangle_hit_point(tri, c.b1, c.b2);
        return SurfaceHit(c.t, pe.p, pe.p_err, triangle_normal(tri), tri.material, c.prim);
    }
    var hit = sphere_point(ray, spheres[c.prim & ~PRIM_SPHERE_BIT], c.t);
    hit.prim = c.prim;
    return hit;
}

fn occluded(ray: Ray, t_max: f32) -> bool {
    return traverse(ray, t_max, true).found;
}
