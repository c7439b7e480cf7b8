// The clearance of a surface point: how far the merge disk about it can reach before it meets
// another surface (`src/transport/clearance.rs`, the same steps).

// Two triangles lie in one plane when their unit normals agree to within this ...
const COPLANAR_COS: f32 = 1e-5;
// ... and the other's vertices lie off the plane by at most this share of the coordinates'
// magnitude (the point's largest coordinate plus the bound, at least 1).
const COPLANAR_OFFSET: f32 = 1e-5;

// The distance from p, a point on primitive prim, to the nearest primitive not in the plane of
// prim (a triangle) or other than prim (a sphere), or bound where none lies nearer.
fn clearance(p: vec3<f32>, prim: u32, bound: f32) -> f32 {
    let own_is_triangle = (prim & PRIM_SPHERE_BIT) == 0u;
    var own = Triangle();
    if own_is_triangle {
        own = triangles[prim];
    }
    let ap = abs(p);
    let tolerance = COPLANAR_OFFSET * max(max(max(ap.x, ap.y), ap.z) + bound, 1.0);
    var best2 = bound * bound;
    // Interior nodes still to visit, each with its box's squared distance from p (bits in .y).
    // At each node the leaves in reach are tested first; then the traversal goes on into the
    // nearest interior child in reach and pushes the others farthest first, so that the nearest
    // of them pops first (at most three per level, `bvh::stack_size`), and a popped node that
    // best2 has since passed is dropped.
    var stack: array<vec2<u32>, STACK_SIZE>;
    var sp = 0u;
    var current = 0u;
    loop {
        let node = nodes[current];
        // Squared distance from p to each child's box.
        var d2 = vec4<f32>();
        for (var c = 0u; c < 4u; c++) {
            let lo = vec3<f32>(node.min_x[c], node.min_y[c], node.min_z[c]);
            let hi = vec3<f32>(node.max_x[c], node.max_y[c], node.max_z[c]);
            let d = max(max(lo - p, p - hi), vec3<f32>(0.0));
            d2[c] = dot(d, d);
        }
        for (var c = 0u; c < 4u; c++) {
            let count = node.count[c];
            if count == EMPTY_SLOT || count == 0u || d2[c] >= best2 {
                continue;
            }
            for (var k = node.child[c]; k < node.child[c] + count; k++) {
                let other = prim_ref(k);
                if other == PRIM_PADDING || other == prim {
                    continue;
                }
                var d2_other = 0.0;
                if (other & PRIM_SPHERE_BIT) != 0u {
                    let s = spheres[other & ~PRIM_SPHERE_BIT];
                    let ds = length(p - s.center) - s.radius;
                    d2_other = ds * ds;
                } else {
                    let t = triangles[other];
                    if own_is_triangle && coplanar(own, t, tolerance) {
                        continue;
                    }
                    let q = closest_point_on_triangle(p, t) - p;
                    d2_other = dot(q, q);
                }
                best2 = min(best2, d2_other);
            }
        }
        var next = vec2<u32>(NO_NODE, 0u);
        let base = sp;
        for (var c = 0u; c < 4u; c++) {
            if node.count[c] != 0u || d2[c] >= best2 {
                continue;
            }
            let entry = vec2<u32>(node.child[c], bitcast<u32>(d2[c]));
            offer_nearest_first(entry, &next, &stack, base, &sp);
        }
        // Descend into the nearest interior child, or pop the most recently pushed one still in
        // reach.
        while next.x == NO_NODE && sp > 0u {
            sp -= 1u;
            if bitcast<f32>(stack[sp].y) < best2 {
                next = stack[sp];
            }
        }
        if next.x == NO_NODE {
            break;
        }
        current = next.x;
    }
    // Where nothing lies nearer, the bound itself: a GPU's square root, which WGSL lets be
    // approximate, may round sqrt(bound²) off it.
    if best2 >= bound * bound {
        return bound;
    }
    return sqrt(best2);
}

// Whether triangle t lies in the plane of own.
fn coplanar(own: Triangle, t: Triangle, tolerance: f32) -> bool {
    return abs(dot(own.n, t.n)) > 1.0 - COPLANAR_COS && abs(dot(own.n, t.v0 - own.v0)) <= tolerance && abs(dot(own.n, t.v1 - own.v0)) <= tolerance && abs(dot(own.n, t.v2 - own.v0)) <= tolerance;
}

// The point of triangle t nearest to p (Ericson, "Real-Time Collision Detection", 5.1.5: the
// Voronoi region of a vertex, an edge or the face).
fn closest_point_on_triangle(p: vec3<f32>, t: Triangle) -> vec3<f32> {
    let a = t.v0;
    let b = t.v1;
    let c = t.v2;
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
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
    return a + ab * (vb * denom) + ac * (vc * denom);
}
