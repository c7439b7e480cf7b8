// Random numbers and warps: `src/math/sampling.rs`, line for line.
// Every block of four random numbers is pcg4d(pixel, sample, dimension block, seed) (Jarzynski and
// Olano 2020) or a 4-D Owen-scrambled Sobol point keyed by the same (Burley 2020), integer
// operations only, so the CPU and the GPU draw the same bits.

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

// How a stream's numbers are drawn (`SamplerKind` in src/math/sampling.rs, `frame.sampler`).
const SAMPLER_INDEPENDENT: u32 = 0u;
const SAMPLER_SOBOL: u32 = 1u;

// The independent randomisations a pixel's Sobol samples are split into (`SOBOL_STREAMS`).
const SOBOL_STREAMS: u32 = 2u;
// Bits of a point's index within one randomisation (`SOBOL_BITS`).
const SOBOL_BITS: u32 = 16u;
// Keeps the Sobol scrambles' hash inputs apart from the independent sampler's (`SOBOL_KEY`).
const SOBOL_KEY: u32 = 0x50B01000u;

// `sobol4_reversed` in src/math/sampling.rs: the xor of the reversed direction numbers of the
// first four Sobol dimensions (`SOBOL_DIRECTIONS`, one line per bit k of the index, which is
// bit 31 - k of index_reversed; tests/sampler.rs checks the numbers are the same).
fn sobol4_reversed(index_reversed: u32) -> vec4<u32> {
    var x = vec4<u32>(0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00000001u, 0x00000001u, 0x00000001u, 0x00000001u), (index_reversed & 0x80000000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00000002u, 0x00000003u, 0x00000003u, 0x00000003u), (index_reversed & 0x40000000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00000004u, 0x00000005u, 0x00000006u, 0x00000004u), (index_reversed & 0x20000000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00000008u, 0x0000000fu, 0x00000009u, 0x0000000au), (index_reversed & 0x10000000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00000010u, 0x00000011u, 0x00000017u, 0x0000001fu), (index_reversed & 0x08000000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00000020u, 0x00000033u, 0x0000003au, 0x0000002eu), (index_reversed & 0x04000000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00000040u, 0x00000055u, 0x00000071u, 0x00000045u), (index_reversed & 0x02000000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00000080u, 0x000000ffu, 0x000000a3u, 0x000000c9u), (index_reversed & 0x01000000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00000100u, 0x00000101u, 0x00000116u, 0x0000011bu), (index_reversed & 0x00800000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00000200u, 0x00000303u, 0x00000339u, 0x000002a4u), (index_reversed & 0x00400000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00000400u, 0x00000505u, 0x00000677u, 0x0000079au), (index_reversed & 0x00200000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00000800u, 0x00000f0fu, 0x000009aau, 0x00000b67u), (index_reversed & 0x00100000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00001000u, 0x00001111u, 0x00001601u, 0x0000101eu), (index_reversed & 0x00080000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00002000u, 0x00003333u, 0x00003903u, 0x0000302du), (index_reversed & 0x00040000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00004000u, 0x00005555u, 0x00007706u, 0x00004041u), (index_reversed & 0x00020000u) != 0u);
    x ^= select(vec4<u32>(0u), vec4<u32>(0x00008000u, 0x0000ffffu, 0x0000aa09u, 0x0000a0c3u), (index_reversed & 0x00010000u) != 0u);
    return x;
}

// Owen scrambling in base 2 of bit-reversed values, each keyed by its seed (`owen_reversed`).
fn owen_reversed(x_in: vec4<u32>, seed: vec4<u32>) -> vec4<u32> {
    var x = x_in;
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> vec4<u32>(16u)) | vec4<u32>(1u);
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

// Block `dim` of sample `sample` of `pixel` under the Sobol sampler, as 32-bit fractions
// (`sobol_draw4_bits`; Burley 2020, section 4: a shuffled, scrambled 4-D Sobol point).
fn sobol_draw4_bits(seed: u32, pixel: u32, sample: u32, dim: u32) -> vec4<u32> {
    // Step 1 - the stream, the randomisation and the point in it.
    let stream = sample % SOBOL_STREAMS;
    let point = sample / SOBOL_STREAMS;
    let randomisation = (point >> SOBOL_BITS) * SOBOL_STREAMS + stream;
    // Step 2 - the seeds.
    let shuffle = pcg4d(vec4<u32>(pixel, randomisation ^ SOBOL_KEY, dim, seed));
    let scramble = pcg4d(shuffle);
    // Step 3 - the shuffle, in the reversed domain: the index's 16 bits are the top 16.
    let index_reversed = owen_reversed(vec4<u32>(reverseBits(point)), shuffle).x & 0xffff0000u;
    // Step 4 - the scrambled point.
    return reverseBits(owen_reversed(sobol4_reversed(index_reversed), scramble));
}

struct Sampler {
    seed: u32,
    pixel: u32,
    sample: u32,
    // SAMPLER_INDEPENDENT or SAMPLER_SOBOL.
    kind: u32,
}

fn draw4(s: Sampler, dim: u32) -> vec4<f32> {
    var h: vec4<u32>;
    if s.kind == SAMPLER_SOBOL {
        h = sobol_draw4_bits(s.seed, s.pixel, s.sample, dim);
    } else {
        h = pcg4d(vec4<u32>(s.pixel, s.sample, dim, s.seed));
    }
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
