// Random numbers and warps: `src/math/sampling.rs`, line for line.
// Every random number is pcg4d(pixel, sample, dimension block, seed) (Jarzynski and Olano 2020),
// integer operations only, so the CPU and the GPU draw the same bits.

fn pcg4d(v_in: vec4<u32>) -> vec4<u32> {
    var v = v_in * 1664525u + 1013904223u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    v ^= v >> vec4<u32>(16u);
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    return v;
}

// The top 24 bits as a float in [0, 1), exactly.
fn u32_to_unit_f32(x: u32) -> f32 {
    return f32(x >> 8u) * (1.0 / 16777216.0);
}

const DIM_CAMERA: u32 = 0u;

fn dim_light(bounce: u32) -> u32 {
    return 1u + 2u * bounce;
}

fn dim_bsdf(bounce: u32) -> u32 {
    return 2u + 2u * bounce;
}

fn dim_light_extra(bounce: u32, j: u32) -> u32 {
    return 0x80000000u + bounce * 256u + j;
}

// Light subpaths' own blocks, from 2^30 up (`DIM_EMISSION` in src/math/sampling.rs): emitter choice
// and point; direction of emission; then one block per bounce (direction, lobe, roulette).
const DIM_EMISSION: u32 = 0x40000000u;
const DIM_EMISSION_DIR: u32 = 0x40000001u;

fn dim_light_bounce(bounce: u32) -> u32 {
    return 0x40000002u + bounce;
}

// BDPT's Russian roulette on the visibility ray of the connection from camera bounce `bounce`
// to light vertex `vertex` (lane vertex % 4).
fn dim_connection(bounce: u32, vertex: u32) -> u32 {
    return 0x60000000u + (bounce << 14u) + vertex / 4u;
}

// VCM's Russian roulette on the merge query at camera bounce k (lane 0).
fn dim_merge(bounce: u32) -> u32 {
    return 0x58000000u + bounce;
}

// BDPT's Russian roulette on the visibility ray of next-event estimation through planar mirror i
// at camera bounce `bounce` (lane i; planar_mirror.wgsl).
fn dim_mirror(bounce: u32) -> u32 {
    return 0x5C000000u + bounce;
}

// Light subpath bounce k: Russian roulette on the splat's visibility ray (lane 0).
fn dim_splat(bounce: u32) -> u32 {
    return 0x50000000u + bounce;
}

struct Sampler {
    seed: u32,
    pixel: u32,
    sample: u32,
}

fn draw4(s: Sampler, dim: u32) -> vec4<f32> {
    let h = pcg4d(vec4<u32>(s.pixel, s.sample, dim, s.seed));
    return vec4<f32>(u32_to_unit_f32(h.x), u32_to_unit_f32(h.y), u32_to_unit_f32(h.z), u32_to_unit_f32(h.w));
}

const PI: f32 = 3.14159265358979323846;
const FRAC_1_PI: f32 = 0.318309886183790671538;

// Cosine-weighted direction about +z (Malley's method); pdf = cos(theta) / pi.
fn sample_cosine_hemisphere(u1: f32, u2: f32) -> vec3<f32> {
    let r = sqrt(u1);
    let sc = sin_cos_turns(u2);
    return vec3<f32>(r * sc.y, r * sc.x, sqrt(max(1.0 - u1, 0.0)));
}

// (sin 2πu, cos 2πu) for u in [0, 1): the nearest quarter turn exactly, the remainder in
// [-π/4, π/4] through Cephes' sinf/cosf minimax polynomials, the quarter turn swapping and
// negating them (`sin_cos_turns` in src/math/sampling.rs).
fn sin_cos_turns(u: f32) -> vec2<f32> {
    let q = floor(u * 4.0 + 0.5);
    let x = (u * 4.0 - q) * (0.5 * PI);
    let x2 = x * x;
    let s = x + x * x2 * (-1.6666655e-1 + x2 * (8.332161e-3 + x2 * -1.9515296e-4));
    let c = 1.0 - 0.5 * x2 + x2 * x2 * (4.1666646e-2 + x2 * (-1.3887316e-3 + x2 * 2.4433157e-5));
    switch u32(q) & 3u {
        case 0u: {
            return vec2<f32>(s, c);
        }
        case 1u: {
            return vec2<f32>(c, -s);
        }
        case 2u: {
            return vec2<f32>(-s, -c);
        }
        default: {
            return vec2<f32>(-c, s);
        }
    }
}

// Uniform point on a triangle as barycentrics (b0, b1, b2); pdf = 1 / area.
fn sample_uniform_triangle(u1: f32, u2: f32) -> vec3<f32> {
    let su = sqrt(u1);
    let b1 = su * (1.0 - u2);
    let b2 = su * u2;
    return vec3<f32>(1.0 - b1 - b2, b1, b2);
}

// Uniform direction on the unit sphere (z uniform in [-1, 1]), pdf = 1 / (4 pi).
fn sample_uniform_sphere(u1: f32, u2: f32) -> vec3<f32> {
    let z = 1.0 - 2.0 * u1;
    let s = sqrt(max(1.0 - z * z, 0.0));
    let phi = 2.0 * PI * u2;
    return vec3<f32>(s * cos(phi), s * sin(phi), z);
}

struct Basis {
    t: vec3<f32>,
    b: vec3<f32>,
}

// Orthonormal basis around a unit normal (Duff et al. 2017).
fn orthonormal_basis(n: vec3<f32>) -> Basis {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return Basis(
        vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        vec3<f32>(b, sign + n.y * n.y * a, -n.y),
    );
}

// The power heuristic with beta = 2 (Veach's thesis, eq. 9.13).
fn power_heuristic(pdf_f: f32, pdf_g: f32) -> f32 {
    let f2 = pdf_f * pdf_f;
    let g2 = pdf_g * pdf_g;
    if f2 + g2 > 0.0 {
        return f2 / (f2 + g2);
    }
    return 0.0;
}
