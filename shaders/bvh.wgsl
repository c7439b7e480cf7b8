// The BVH traversal: `src/bvh.rs`, one traversal with a closest-hit and an any-hit mode: both
// children's boxes tested at once, the nearer first, an explicit stack in a private array.

// Specialised by the host to the BVH's depth (`bvh::depth`): the traversal pushes at most one
// node per level.
const STACK_SIZE: u32 = 64u;

// "No interior child to visit next" (`None` in src/bvh.rs).
const NO_NODE: u32 = 0xffffffffu;

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
// At each node both children's boxes are tested at once; the hit children are taken nearer
// first: a leaf's primitives are tested at once, the first interior child is visited next and a
// second one is pushed with its entry distance (bits in .y), so a missed child is never pushed
// and a pushed one that a closer hit has since passed is dropped when popped.
fn traverse(ray: Ray, t_max: f32, any_hit: bool) -> Candidate {
    var best = Candidate(false, t_max, 0u, 0.0, 0.0);
    let inv_d = safe_inverse(ray.d);
    var stack: array<vec2<u32>, STACK_SIZE>;
    var sp = 0u;
    var current = 0u;
    loop {
        let node = nodes[current];
        let t_enter = intersect_aabb_pair(node, ray.o, inv_d, best.t);
        let near = select(0u, 1u, t_enter.y < t_enter.x);
        var next = NO_NODE;
        for (var i = 0u; i < 2u; i++) {
            let c = select(1u - near, near, i == 0u);
            // A missed box, or one that a hit in the nearer child's leaf has since passed.
            if t_enter[c] < 0.0 || t_enter[c] > best.t {
                continue;
            }
            let count = node.count[c];
            if count == 0u {
                if next == NO_NODE {
                    next = node.child[c];
                } else {
                    stack[sp] = vec2<u32>(node.child[c], bitcast<u32>(t_enter[c]));
                    sp += 1u;
                }
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
        // Descend into the first interior child, or pop the most recently pushed one that the
        // ray still enters before best.t.
        if next == NO_NODE {
            while sp > 0u {
                sp -= 1u;
                if bitcast<f32>(stack[sp].y) <= best.t {
                    next = stack[sp].x;
                    break;
                }
            }
            if next == NO_NODE {
                break;
            }
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
