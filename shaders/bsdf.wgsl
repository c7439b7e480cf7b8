// The three scattering models: `src/transport/bsdf.rs`, line for line.

// Unpolarised Fresnel reflectance of a smooth dielectric (exact, not Schlick); 1 under total
// internal reflection (pbrt-v4 eq. 9.6).
fn fresnel_dielectric(cos_i_in: f32, eta_in: f32) -> f32 {
    var cos_i = clamp(cos_i_in, -1.0, 1.0);
    var eta = eta_in;
    if cos_i < 0.0 {
        // Arriving from inside: swap the media.
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(max(1.0 - sin2_t, 0.0));
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (r_parl * r_parl + r_perp * r_perp);
}

fn reflect_about(wo: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return -wo + 2.0 * dot(wo, n) * n;
}

struct Refraction {
    possible: bool,
    wt: vec3<f32>,
    etap: f32,
}

// Snell refraction of wo through a boundary with normal n and relative index eta (inside over
// outside); etap is the index of the entered side over the left side.
fn refract_through(wo: vec3<f32>, n_in: vec3<f32>, eta_in: f32) -> Refraction {
    var cos_i = dot(wo, n_in);
    var n = n_in;
    var eta = eta_in;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = max(1.0 - cos_i * cos_i, 0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return Refraction(false, vec3<f32>(0.0), 1.0);
    }
    let cos_t = sqrt(max(1.0 - sin2_t, 0.0));
    let wt = -wo / eta + (cos_i / eta - cos_t) * n;
    return Refraction(true, normalize(wt), eta);
}

// Which quantity a path carries (`Transport` in src/transport/bsdf.rs): camera subpaths radiance, light
// subpaths importance (flux), which refraction does not scale by 1 / eta^2.
const TRANSPORT_RADIANCE: u32 = 0u;
const TRANSPORT_IMPORTANCE: u32 = 1u;

// The two-sided Lambertian BSDF for a pair of directions (`DiffuseEval` in src/transport/bsdf.rs).
struct DiffuseEval {
    // albedo / pi where wo and wi lie on one side, else 0.
    f: vec3<f32>,
    // The cosine toward wi (0 where f is).
    cos_i: f32,
    // Solid-angle density of wi when sampling from wo: cos_i / pi.
    pdf: f32,
    // The reverse: cos_o / pi.
    pdf_rev: f32,
}

// Lambert of albedo `albedo` at a surface whose unit normal n_facing points to wo's side.
fn eval_diffuse(albedo: vec3<f32>, n_facing: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> DiffuseEval {
    let cos_i = dot(n_facing, wi);
    if cos_i <= 0.0 {
        return DiffuseEval(vec3<f32>(0.0), 0.0, 0.0, 0.0);
    }
    return DiffuseEval(albedo * FRAC_1_PI, cos_i, cos_i * FRAC_1_PI, max(dot(n_facing, wo), 0.0) * FRAC_1_PI);
}

struct BsdfSample {
    wi: vec3<f32>,
    // f |cos theta_i| / pdf.
    weight: vec3<f32>,
    // Solid-angle pdf; 0 for a specular (Dirac) lobe.
    pdf: f32,
    // etap^2 of a refraction (1 otherwise), for Russian roulette.
    eta2: f32,
}

fn sample_bsdf(m: Material, n: vec3<f32>, wo: vec3<f32>, u: vec4<f32>, transport: u32) -> BsdfSample {
    if m.kind == KIND_MIRROR {
        return BsdfSample(reflect_about(wo, n), m.color, 0.0, 1.0);
    }
    if m.kind == KIND_GLASS {
        // Choose reflection with probability F, refraction with 1 - F: the weight of each lobe
        // is then exactly its Fresnel factor over its probability, 1.
        let f = fresnel_dielectric(dot(wo, n), m.ior);
        if u.z < f {
            return BsdfSample(reflect_about(wo, n), vec3<f32>(1.0), 0.0, 1.0);
        }
        // Radiance scales by 1 / etap^2 across the boundary (pbrt-v4 eq. 9.17); flux
        // (importance transport, light subpaths) does not.
        let r = refract_through(wo, n, m.ior);
        if !r.possible {
            return BsdfSample(reflect_about(wo, n), vec3<f32>(1.0), 0.0, 1.0);
        }
        let eta2 = r.etap * r.etap;
        if transport == TRANSPORT_IMPORTANCE {
            return BsdfSample(r.wt, m.color, 0.0, eta2);
        }
        return BsdfSample(r.wt, m.color / eta2, 0.0, eta2);
    }
    // Diffuse, and emitters that also reflect: Lambert, f = albedo / pi, sampled with the
    // cosine-weighted pdf cos theta / pi, so the weight is the albedo.
    let nf = select(n, -n, dot(wo, n) < 0.0);
    let local = sample_cosine_hemisphere(u.x, u.y);
    let basis = orthonormal_basis(nf);
    // Unit to rounding: an orthonormal basis times a unit vector.
    let wi = local.x * basis.t + local.y * basis.b + local.z * nf;
    return BsdfSample(wi, m.color, local.z * FRAC_1_PI, 1.0);
}
