//! Random numbers and the warps that turn them into directions and points.
//!
//! Every random number is a pure function of (seed, pixel, sample index, dimension): a
//! counter-based hash, not a stateful generator. So an image does not depend on how pixels are
//! scheduled over threads, and `shaders/sampling.wgsl` draws the very same numbers bit for bit
//! (only 32-bit integer multiply, add, xor and shift are used, which WGSL defines exactly).
//!
//! The hash is `pcg4d` from Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 9(3),
//! 2020: a 4-in/4-out permutation of u32 vectors with good avalanche on every input lane. One call
//! gives four numbers, so a *dimension* here names a block of four: block 0 is the camera, and
//! bounce `k` uses blocks `1 + 2k` (light sampling and roulette) and `2 + 2k` (BSDF sampling).

use glam::Vec3;
use std::f32::consts::FRAC_PI_2;

/// `pcg4d`: one round of an LCG on each lane, then two rounds of lane mixing around a xorshift.
#[inline]
pub fn pcg4d(v: [u32; 4]) -> [u32; 4] {
    let mut v = v.map(|x| x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223));
    v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[3]));
    v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
    v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    v[3] = v[3].wrapping_add(v[1].wrapping_mul(v[2]));
    v = v.map(|x| x ^ (x >> 16));
    v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[3]));
    v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
    v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    v[3] = v[3].wrapping_add(v[1].wrapping_mul(v[2]));
    v
}

/// The top 24 bits as a float in [0, 1): every value is exactly representable in f32, so the
/// conversion is exact on any backend.
#[inline]
pub fn u32_to_unit_f32(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Dimension blocks, named so the integrator and the shader say which numbers they use.
pub const DIM_CAMERA: u32 = 0;
/// First block of bounce `k`: emitter choice, point on the emitter (2), Russian roulette.
#[inline]
pub fn dim_light(bounce: u32) -> u32 {
    1 + 2 * bounce
}
/// Second block of bounce `k`: BSDF direction (2), lobe choice (reflect or refract), and for
/// BDPT the Russian roulette on the next-event ray.
#[inline]
pub fn dim_bsdf(bounce: u32) -> u32 {
    2 + 2 * bounce
}
/// Shadow rays beyond the first (`--light-samples`): block of light sample `j` in 1..256 at
/// bounce `k`, in the upper half of the block space, so that one light sample per vertex draws
/// exactly the numbers it always did. (Blocks would collide only past 2^22 bounces, which
/// Russian roulette with survival ≤ 0.95 makes a probability below 10^-50000.)
#[inline]
pub fn dim_light_extra(bounce: u32, j: u32) -> u32 {
    0x8000_0000u32
        .wrapping_add(bounce.wrapping_mul(256))
        .wrapping_add(j)
}
/// Light subpaths (light tracing, BDPT) draw from blocks of their own, from 2^30 up, keyed by
/// the same (seed, index, iteration) as the camera subpath of pixel `index`: so a camera subpath
/// of BDPT draws exactly the numbers a path-traced sample does, and its light subpath is
/// independent of it. Block [`DIM_EMISSION`]: emitter choice, point on the emitter (2), Russian
/// roulette on the light point's splat.
pub const DIM_EMISSION: u32 = 0x4000_0000;
/// The direction of emission (2), unused (2).
pub const DIM_EMISSION_DIR: u32 = 0x4000_0001;
/// Light subpath bounce `k`: BSDF direction (2), lobe choice, Russian roulette.
#[inline]
pub fn dim_light_bounce(bounce: u32) -> u32 {
    0x4000_0002u32.wrapping_add(bounce)
}
/// BDPT's Russian roulette on the visibility ray of the connection from camera bounce `bounce`
/// to light vertex `vertex`: lane `vertex % 4` of this block (blocks from 3 · 2^29 up; distinct
/// for 2^14 bounces and 2^16 vertices, far beyond any path Russian roulette lets through).
#[inline]
pub fn dim_connection(bounce: u32, vertex: u32) -> u32 {
    0x6000_0000u32
        .wrapping_add(bounce.wrapping_shl(14))
        .wrapping_add(vertex / 4)
}
/// Light subpath bounce `k`: Russian roulette on the visibility ray of the splat from the vertex
/// it reaches (lane 0).
#[inline]
pub fn dim_splat(bounce: u32) -> u32 {
    0x5000_0000u32.wrapping_add(bounce)
}
/// VCM's Russian roulette on the merge query at camera bounce `bounce` (lane 0;
/// `subpath::merge_survival`).
#[inline]
pub fn dim_merge(bounce: u32) -> u32 {
    0x5800_0000u32.wrapping_add(bounce)
}
/// BDPT's Russian roulette on the visibility ray of next-event estimation through
/// planar mirror `i` at camera bounce `bounce` (lane `i`; `crate::transport::planar_mirror`).
#[inline]
pub fn dim_mirror(bounce: u32) -> u32 {
    0x5C00_0000u32.wrapping_add(bounce)
}
/// The most shadow rays per diffuse vertex (`--light-samples`): `j` fits a byte of
/// [`dim_light_extra`].
pub const MAX_LIGHT_SAMPLES: u32 = 256;

/// The random stream of one camera sample: (seed, pixel, sample index) fixed, the dimension
/// block chosen per draw.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    pub seed: u32,
    pub pixel: u32,
    pub sample: u32,
}

impl Sampler {
    pub fn new(seed: u32, pixel: u32, sample: u32) -> Self {
        Self {
            seed,
            pixel,
            sample,
        }
    }

    /// Four uniform numbers in [0, 1) for dimension block `dim`.
    #[inline]
    pub fn draw4(&self, dim: u32) -> [f32; 4] {
        pcg4d([self.pixel, self.sample, dim, self.seed]).map(u32_to_unit_f32)
    }
}

/// (sin 2πu, cos 2πu) for u in [0, 1): the angle is reduced to the nearest quarter turn exactly
/// (u·4 minus an integer), the remainder x in [−π/4, π/4] goes through the minimax polynomials of
/// Cephes' `sinf`/`cosf` (relative error about 1e-7 there), and the quarter turn swaps and
/// negates them. Four times cheaper than libm's `sincosf` on the path vertex's critical path,
/// and written with plain arithmetic so that `shaders/sampling.wgsl` computes the same.
#[inline]
pub fn sin_cos_turns(u: f32) -> (f32, f32) {
    let q = (u * 4.0 + 0.5).floor();
    let x = (u * 4.0 - q) * FRAC_PI_2;
    let x2 = x * x;
    let s = x + x * x2 * (-1.666_665_5e-1 + x2 * (8.332_161e-3 + x2 * -1.951_529_6e-4));
    let c =
        1.0 - 0.5 * x2 + x2 * x2 * (4.166_664_6e-2 + x2 * (-1.388_731_6e-3 + x2 * 2.443_315_7e-5));
    match q as u32 & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// Cosine-weighted direction about +z (Malley's method: a uniform point on the unit disk, lifted
/// to the hemisphere); pdf = cos(theta) / pi with respect to solid angle. The result is unit
/// length to rounding (x² + y² = u1, z² = 1 − u1).
#[inline]
pub fn sample_cosine_hemisphere(u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let (sin_phi, cos_phi) = sin_cos_turns(u2);
    let z = (1.0 - u1).max(0.0).sqrt();
    Vec3::new(r * cos_phi, r * sin_phi, z)
}

/// Uniform point on a triangle as barycentrics (b0, b1, b2): the square-root warp,
/// pdf = 1 / area with respect to area.
#[inline]
pub fn sample_uniform_triangle(u1: f32, u2: f32) -> (f32, f32, f32) {
    let su = u1.sqrt();
    let b1 = su * (1.0 - u2);
    let b2 = su * u2;
    (1.0 - b1 - b2, b1, b2)
}

/// Uniform direction on the unit sphere (Archimedes: z uniform in [-1, 1]), pdf = 1 / (4 pi)
/// with respect to solid angle, so a point on a sphere of radius r has area pdf 1 / (4 pi r^2).
#[inline]
pub fn sample_uniform_sphere(u1: f32, u2: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u1;
    let s = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    Vec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// An orthonormal basis (t, b) around a unit normal n: Duff et al., "Building an Orthonormal
/// Basis, Revisited", JCGT 6(1), 2017 (branchless, no singularity).
#[inline]
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bt = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    (t, bt)
}

/// The power heuristic with beta = 2 (Veach's thesis, eq. 9.13), for one sample from each of
/// two strategies: the weight of the strategy with pdf `pdf_f` against the one with `pdf_g`.
#[inline]
pub fn power_heuristic(pdf_f: f32, pdf_g: f32) -> f32 {
    let f2 = pdf_f * pdf_f;
    let g2 = pdf_g * pdf_g;
    if f2 + g2 > 0.0 {
        f2 / (f2 + g2)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_floats_lie_in_the_half_open_interval() {
        assert_eq!(u32_to_unit_f32(0), 0.0);
        assert!(u32_to_unit_f32(u32::MAX) < 1.0);
    }

    #[test]
    fn streams_differ_in_every_key() {
        let base = Sampler::new(1, 2, 3).draw4(4);
        assert_ne!(base, Sampler::new(9, 2, 3).draw4(4));
        assert_ne!(base, Sampler::new(1, 9, 3).draw4(4));
        assert_ne!(base, Sampler::new(1, 2, 9).draw4(4));
        assert_ne!(base, Sampler::new(1, 2, 3).draw4(9));
    }

    /// The mean of N uniform numbers has standard error 1/sqrt(12 N); a lane that is off by
    /// more than 5 s.e. is not uniform (p < 6e-7 per lane for a correct hash).
    #[test]
    fn every_lane_has_mean_one_half() {
        let n = 200_000u32;
        let mut sums = [0.0f64; 4];
        for i in 0..n {
            let u = Sampler::new(7, i % 4096, i / 4096).draw4(3);
            for k in 0..4 {
                sums[k] += u[k] as f64;
            }
        }
        let se = (1.0 / (12.0 * n as f64)).sqrt();
        for s in sums {
            let z = (s / n as f64 - 0.5) / se;
            assert!(z.abs() < 5.0, "lane mean off by {z} s.e.");
        }
    }

    /// Over every 24-bit u the random numbers take (u = k / 2^24), the polynomial sine and
    /// cosine of 2πu stay within 2.5e-7 of the f64 values: the accuracy of f32 itself near 1.
    #[test]
    fn sin_cos_turns_matches_f64_to_f32_accuracy() {
        let mut worst = 0.0f64;
        for k in 0..(1u32 << 24) {
            let u = k as f32 / 16_777_216.0;
            let (s, c) = sin_cos_turns(u);
            let phi = 2.0 * std::f64::consts::PI * u as f64;
            worst = worst.max(
                (s as f64 - phi.sin())
                    .abs()
                    .max((c as f64 - phi.cos()).abs()),
            );
        }
        assert!(worst < 2.5e-7, "worst error {worst:e}");
    }

    #[test]
    fn orthonormal_basis_is_orthonormal() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
        ] {
            let (t, b) = orthonormal_basis(n);
            assert!((t.length() - 1.0).abs() < 1e-6);
            assert!((b.length() - 1.0).abs() < 1e-6);
            assert!(t.dot(b).abs() < 1e-6 && t.dot(n).abs() < 1e-6 && b.dot(n).abs() < 1e-6);
        }
    }
}
