// The BVH traversal: `src/bvh.rs`, one traversal with a closest-hit and an any-hit mode: the four
// children's boxes tested at once, nearest first, an explicit stack in a private array.

// Specialised by the host to `bvh::stack_size`: the traversal pushes at most three nodes per
// level.
const STACK_SIZE: u32 = 64u;

// "No interior child to visit next" (`None` in src/bvh.rs).
const NO_NODE: u32 = 0xffffffffu;

// The sort key of a missed child slot: a finite float above every entry distance.
const MISS_KEY: f32 = F32_MAX;

// Child slots ordered by entry distance, nearest first, misses last. Each slot's key is its
// entry distance with the slot number in its two lowest mantissa bits (a hit's t >= 0, so keys
// order as the distances rounded down to 4 ulp do), or MISS_KEY; five compare-exchanges sort the
// four keys (a sorting network: three rounds of four-wide min/max, no branches).
fn nearest_first(t_enter: vec4<f32>) -> vec4<f32> {
    let t = select(t_enter, vec4<f32>(MISS_KEY), t_enter < vec4<f32>(0.0));
    var k = bitcast<vec4<f32>>((bitcast<vec4<u32>>(t) & vec4<u32>(~3u)) | vec4<u32>(0u, 1u, 2u, 3u));
    // (0, 1) and (2, 3); then (0, 2) and (1, 3); then (1, 2).
    var p = k.yxwz;
    k = select(max(k, p), min(k, p), vec4<bool>(true, false, true, false));
    p = k.zwxy;
    k = select(max(k, p), min(k, p), vec4<bool>(true, true, false, false));
    p = k.xzyw;
    return select(max(k, p), min(k, p), vec4<bool>(true, true, false, false));
}

// The child slot of a sort key.
fn slot(key: f32) -> u32 {
    return bitcast<u32>(key) & 3u;
}

// The entry distance of a sort key, rounded down by up to 3 ulp.
fn key_distance(key: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(key) & ~3u);
}

// Entry k of the primitive references (packed four to a vec4<u32>).
fn prim_ref(k: u32) -> u32 {
    return prims[k >> 2u][k & 3u];
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
// t_max). Any-hit mode (any_hit = true), for shadow rays: stops at the first hit within the
// open segment (0, t_max), not counting hits within their own error bound of t_max.
//
// At each node the four children's boxes are tested at once and the hit children sorted by
// entry distance. The leaves among them are tested first, nearest first, so that their hits
// lower best.t before anything is pushed; then the nearest interior child is visited next and
// the others are pushed farthest first (so nearer ones pop first), each with its entry distance
// (bits in .y): a missed child is never pushed and a pushed one that a closer hit has since
// passed is dropped when popped.
fn traverse(ray: Ray, t_max: f32, any_hit: bool) -> Candidate {
    var best = Candidate(false, t_max, 0u, 0.0, 0.0);
    let inv_d = safe_inverse(ray.d);
    var stack: array<vec2<u32>, STACK_SIZE>;
    var sp = 0u;
    var current = 0u;
    loop {
        let node = nodes[current];
        let t_enter = intersect_aabb4(node, ray.o, inv_d, best.t);
        let order = nearest_first(t_enter);
        for (var i = 0u; i < 4u; i++) {
            let c = slot(order[i]);
            // In key order, after a miss or a key past best.t come only misses and farther boxes
            // (a key is its distance rounded down, so none is skipped that the ray enters before
            // best.t).
            if t_enter[c] < 0.0 || key_distance(order[i]) > best.t {
                break;
            }
            let count = node.count[c];
            if count == 0u {
                continue;
            }
            for (var k = node.child[c]; k < node.child[c] + count; k++) {
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
                    } else if t < best.t {
                        best = Candidate(true, t, prim, b1, b2);
                    }
                }
            }
        }
        var next = NO_NODE;
        var t_next = 0.0;
        for (var i = 0u; i < 4u; i++) {
            let c = slot(order[3u - i]);
            if t_enter[c] < 0.0 || node.count[c] != 0u || t_enter[c] > best.t {
                continue;
            }
            if next != NO_NODE {
                stack[sp] = vec2<u32>(next, bitcast<u32>(t_next));
                sp += 1u;
            }
            next = node.child[c];
            t_next = t_enter[c];
        }
        // Descend into the nearest interior child, or pop the most recently pushed one that the
        // ray still enters before best.t.
        while next == NO_NODE && sp > 0u {
            sp -= 1u;
            if bitcast<f32>(stack[sp].y) <= best.t {
                next = stack[sp].x;
            }
        }
        if next == NO_NODE {
            break;
        }
        current = next;
    }
    return best;
}

// The closest hit as a surface: point, error bound, normal, material.
fn surface_hit(ray: Ray, c: Candidate) -> SurfaceHit {
    if (c.prim & PRIM_SPHERE_BIT) == 0u {
        let tri = triangles[c.prim];
        let pe = triangle_point(tri, c.b1, c.b2);
        return SurfaceHit(c.t, pe.p, pe.p_err, triangle_normal(tri), tri.material, c.prim);
    }
    var hit = sphere_point(ray, spheres[c.prim & ~PRIM_SPHERE_BIT], c.t);
    hit.prim = c.prim;
    return hit;
}

fn occluded(ray: Ray, t_max: f32) -> bool {
    return traverse(ray, t_max, true).found;
}
