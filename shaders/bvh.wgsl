// The BVH traversal: `src/bvh.rs`, one traversal with a closest-hit and an any-hit mode, near
// child first, an explicit stack in a private array.

// Specialised by the host to the BVH's depth (`bvh::depth`): the traversal pushes at most one
// node per level.
const STACK_SIZE: u32 = 64u;

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
fn traverse(ray: Ray, t_max: f32, any_hit: bool) -> Candidate {
    var best = Candidate(false, t_max, 0u, 0.0, 0.0);
    let inv_d = safe_inverse(ray.d);
    let dir_is_neg = vec3<bool>(inv_d.x < 0.0, inv_d.y < 0.0, inv_d.z < 0.0);
    var stack: array<u32, STACK_SIZE>;
    var sp = 0u;
    var current = 0u;
    loop {
        let node = nodes[current];
        if intersect_aabb(node.min, node.max, ray.o, inv_d, best.t) {
            let count = node.count_axis & 0xffffu;
            if count > 0u {
                for (var k = node.offset; k < node.offset + count; k++) {
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
            } else {
                // Visit the near child first; remember the far one.
                let axis = node.count_axis >> 16u;
                if dir_is_neg[axis] {
                    stack[sp] = current + 1u;
                    current = node.offset;
                } else {
                    stack[sp] = node.offset;
                    current = current + 1u;
                }
                sp += 1u;
                continue;
            }
        }
        if sp == 0u {
            break;
        }
        sp -= 1u;
        current = stack[sp];
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
