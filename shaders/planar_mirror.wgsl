// Planar mirrors, and next-event estimation through them: `src/transport/planar_mirror.rs` again, with the
// same names. The light point of next-event estimation reflected in a planar mirror's plane is a
// light of the same area density; the path x -> m -> y through the mirror point m is taken by
// that strategy alone (weight 1), and by no other: a partition of the paths whose light end is a
// light point, a planar mirror and a diffuse vertex, which keeps the estimate unbiased. The host
// finds the planar mirrors and marks each triangle with its plane (`Triangle::planar_mirror`).

// The slack of `image`'s bounds test beyond the plane's tolerance, per unit of the magnitudes m is
// computed from (|x| and |y' - x|): 16 f32 epsilons, 2^-19 (the closest-hit ray decides).
const BOUNDS_SLACK: f32 = 1.9073486328125e-6;

// Marks a triangle on no planar mirror (Triangle::planar_mirror).
const NO_PLANAR_MIRROR: u32 = 0xffffffffu;

// Whether the method takes next-event estimation through planar mirrors: one that `connects`
// (BDPT's strategies) and does not merge, in a scene with planar mirrors: BDPT, and vcm with the
// radius 0 (`takes_mirror_light` in src/transport/planar_mirror.rs says why not VCM that merges).
fn takes_mirror_light(connects: bool) -> bool {
    return connects && !merges() && frame.planar_mirror_count > 0u;
}

// The planar mirror that primitive `prim` (a SurfaceHit's) is part of, or NO_PLANAR_MIRROR.
fn planar_mirror_of(prim: u32) -> u32 {
    if frame.planar_mirror_count == 0u || (prim & PRIM_SPHERE_BIT) != 0u {
        return NO_PLANAR_MIRROR;
    }
    return triangles[prim].planar_mirror;
}

// Whether a path whose light end is the light point, then the vertex of primitive `first_prim`,
// then a vertex that `second_diffuse` says is diffuse, is one that next-event estimation through
// a planar mirror takes (and no other strategy).
fn starts_by_a_mirror(first_prim: u32, second_diffuse: bool) -> bool {
    return second_diffuse && planar_mirror_of(first_prim) != NO_PLANAR_MIRROR;
}

// The light point y (normal n_y) seen from x by way of a mirror (`image`).
struct MirrorImage {
    // Whether x and y are strictly on the same side of the plane and m within the bounds.
    found: bool,
    // The image y' of y in the plane, and its normal.
    y_image: vec3<f32>,
    n_image: vec3<f32>,
}

// The light point y (normal n_y) seen from x by way of `mirror`: the image y' of y in the
// mirror's plane and the image's normal; not found where x and y are not strictly on the same
// side of the plane or the point m where the segment x y' crosses the plane falls outside the
// mirror's bounds. Whether m is on the mirror and the segment x m is clear is for a closest-hit
// ray to say.
fn image(mirror: PlanarMirror, x: vec3<f32>, y: vec3<f32>, n_y: vec3<f32>) -> MirrorImage {
    var r = MirrorImage(false, vec3<f32>(0.0), vec3<f32>(0.0));
    // Signed distances to the plane.
    let sx = dot(mirror.n, x) - mirror.d;
    let sy = dot(mirror.n, y) - mirror.d;
    if sx * sy <= 0.0 {
        return r;
    }
    r.y_image = y - 2.0 * sy * mirror.n;
    r.n_image = n_y - 2.0 * dot(mirror.n, n_y) * mirror.n;
    // The segment x y' crosses the plane where the signed distance goes from sx to -sy.
    let m = x + (r.y_image - x) * (sx / (sx + sy));
    let scale = max_element(abs(x)) + max_element(abs(r.y_image - x));
    let slack = vec3<f32>(mirror.tolerance + BOUNDS_SLACK * scale);
    r.found = all(m >= mirror.lo - slack) && all(m <= mirror.hi + slack);
    return r;
}
