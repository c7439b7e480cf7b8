// Area lights: `src/transport/light.rs`, line for line.

struct LightSample {
    p: vec3<f32>,
    p_err: vec3<f32>,
    n: vec3<f32>,
    le: vec3<f32>,
    // pmf(emitter) / area.
    pdf_area: f32,
}

// The emitter-table row whose CDF interval holds u (first row with cdf > u).
fn choose_emitter(u: f32) -> u32 {
    // The first of rows 0..rows - 1 with cdf > u, or rows - 1: `first_above` in src/transport/light.rs,
    // each halving a select (the answer lies in base..=base + size, every row before base has
    // cdf <= u).
    let candidates = frame.num_emitters - 1u;
    if candidates == 0u {
        return 0u;
    }
    var base = 0u;
    var size = candidates;
    while size > 1u {
        let half = size / 2u;
        base = select(base, base + half, emitters[base + half].cdf <= u);
        size -= half;
    }
    return base + select(0u, 1u, emitters[base].cdf <= u);
}

// An emitter chosen in proportion to its power, then a point uniformly on its area: on a
// triangle by the square-root warp, on a sphere by a uniform direction from its centre.
fn sample_emitter(u_select: f32, u1: f32, u2: f32) -> LightSample {
    let row = emitters[choose_emitter(u_select)];
    let pdf_area = row.pmf / row.area;
    if (row.prim & PRIM_SPHERE_BIT) != 0u {
        let sphere = spheres[row.prim & ~PRIM_SPHERE_BIT];
        let d = sample_uniform_sphere(u1, u2);
        let pe = sphere_point_at(sphere, sphere.radius * d);
        return LightSample(pe.p, pe.p_err, sphere_normal(sphere, d), materials[sphere.material].emission, pdf_area);
    }
    let tri = triangles[row.prim];
    let b = sample_uniform_triangle(u1, u2);
    let pe = triangle_point(tri, b.y, b.z);
    return LightSample(pe.p, pe.p_err, triangle_normal(tri), materials[tri.material].emission, pdf_area);
}

// The area density with which sample_emitter picks points on primitive prim (a `prims`
// reference, as SurfaceHit.prim).
fn emitter_pdf_area(prim: u32) -> f32 {
    var row: u32;
    if (prim & PRIM_SPHERE_BIT) != 0u {
        row = spheres[prim & ~PRIM_SPHERE_BIT].emitter;
    } else {
        row = triangles[prim].emitter;
    }
    if row == NOT_AN_EMITTER {
        return 0.0;
    }
    let e = emitters[row];
    return e.pmf / e.area;
}

// p_omega = p_A r^2 / |cos theta_l|.
fn area_to_solid_angle(pdf_area: f32, dist2: f32, cos_light: f32) -> f32 {
    return pdf_area * dist2 / abs(cos_light);
}

// Where a light subpath starts: a point on an emitter and a direction from its front
// (`EmissionSample`).
struct EmissionSample {
    point: LightSample,
    dir: vec3<f32>,
    cos: f32,
    // cos / pi.
    pdf_dir: f32,
}

// An emitter point chosen as sample_emitter chooses it, then a cosine-distributed direction from
// its front (`sample_emission`).
fn sample_emission(u_point: vec4<f32>, u_dir: vec4<f32>) -> EmissionSample {
    let point = sample_emitter(u_point.x, u_point.y, u_point.z);
    let local = sample_cosine_hemisphere(u_dir.x, u_dir.y);
    let basis = orthonormal_basis(point.n);
    return EmissionSample(point, local.x * basis.t + local.y * basis.b + local.z * point.n, local.z, local.z * FRAC_1_PI);
}

// Next-event estimation's link from a surface point to a point on the emitters
// (`EmitterLink` in src/transport/light.rs); `found` false where either side faces away.
struct EmitterLink {
    found: bool,
    shadow: Ray,
    le: vec3<f32>,
    cos_s: f32,
    light_pdf: f32,
}

// Links the point p (error bound p_err, geometric normal n, n_facing on the shaded side) to the
// emitter point ls: the shadow ray between the two points offset off their surfaces, t in (0, 1).
fn link_to_emitter(p: vec3<f32>, p_err: vec3<f32>, n: vec3<f32>, n_facing: vec3<f32>, ls: LightSample) -> EmitterLink {
    let to_light = ls.p - p;
    let dist2 = dot(to_light, to_light);
    let wi = to_light / sqrt(dist2);
    let cos_s = dot(n_facing, wi);
    let cos_l = -dot(ls.n, wi);
    if !(cos_s > 0.0 && cos_l > 0.0 && dist2 > 0.0) {
        return EmitterLink(false, Ray(p, wi), vec3<f32>(0.0), 0.0, 0.0);
    }
    let origin = offset_ray_origin(p, p_err, n, wi);
    let light_point = offset_ray_origin(ls.p, ls.p_err, ls.n, -wi);
    return EmitterLink(true, Ray(origin, light_point - origin), ls.le, cos_s, area_to_solid_angle(ls.pdf_area, dist2, cos_l));
}
