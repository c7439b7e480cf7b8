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
//!
//! A block's four numbers are either independent hashes or a 4-D Owen-scrambled Sobol point
//! ([`SamplerKind`]); either way they are a function of (seed, pixel, sample, block) alone.

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
/// the same numbers as a render without `--light-samples`. (Blocks would collide only past 2^22 bounces, which
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

/// How a stream's numbers are drawn (`--sampler`).
///
/// - `Independent`: every block is [`pcg4d`] of (pixel, sample, block, seed), independent of
///   every other.
/// - `Sobol`: every block is a 4-D Owen-scrambled Sobol point (Burley 2020, "Practical
///   Hash-based Owen Scrambling", JCGT 9(4)), *padded*: each block of each pixel has its own
///   shuffle of the point order and its own scramble, both hashed from (pixel, block, seed), so
///   the blocks of one path are as independent of each other as under `Independent`, while the
///   samples of one block in one pixel are stratified against each other. No block lies past
///   a table: the four Sobol dimensions serve every block.
///
///   The samples of a pixel are two independent randomisations of the sequence, interleaved:
///   sample `i` is point `i / 2` of stream `i % 2`. Their means are independent estimates, which
///   is what the film's standard errors need (`PixelStats::var_of_mean_from_streams`): the samples within a
///   stream are not independent, and their sample variance does not measure the mean's error.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum SamplerKind {
    #[default]
    Independent,
    Sobol,
}

impl SamplerKind {
    /// The name on the command line and in metadata.
    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Independent => "independent",
            SamplerKind::Sobol => "sobol",
        }
    }

    /// `SAMPLER_*` in `shaders/sampling.wgsl`.
    pub fn code(self) -> u32 {
        self as u32
    }
}

impl std::fmt::Display for SamplerKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The random stream of one camera sample: (seed, pixel, sample index) fixed, the dimension
/// block chosen per draw.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    pub seed: u32,
    pub pixel: u32,
    pub sample: u32,
    pub kind: SamplerKind,
}

impl Sampler {
    /// The independent stream (the default sampler).
    pub fn new(seed: u32, pixel: u32, sample: u32) -> Self {
        Self::of(SamplerKind::Independent, seed, pixel, sample)
    }

    /// The stream of `kind`.
    pub fn of(kind: SamplerKind, seed: u32, pixel: u32, sample: u32) -> Self {
        Self {
            seed,
            pixel,
            sample,
            kind,
        }
    }

    /// Four uniform numbers in [0, 1) for dimension block `dim`.
    #[inline]
    pub fn draw4(&self, dim: u32) -> [f32; 4] {
        match self.kind {
            SamplerKind::Independent => {
                pcg4d([self.pixel, self.sample, dim, self.seed]).map(u32_to_unit_f32)
            }
            SamplerKind::Sobol => {
                sobol_draw4_bits(self.seed, self.pixel, self.sample, dim).map(u32_to_unit_f32)
            }
        }
    }
}

/// The independent randomisations a pixel's Sobol samples are split into (see [`SamplerKind`]).
pub const SOBOL_STREAMS: u32 = 2;
// The lanes' Sobol points (`lanes::sobol_draw4_bits`) take the stream as the sample's low bit.
const _: () = assert!(SOBOL_STREAMS == 2);

/// Bits of a point's index within one randomisation: 2^16 points of a stream share a shuffle
/// and scramble, and the next 2^16 are a new randomisation (keyed by the index's upper bits),
/// so a Sobol point costs 16 steps of the generator whatever the sample count.
pub const SOBOL_BITS: u32 = 16;

/// Keeps the Sobol scrambles' hash inputs apart from the independent sampler's: the
/// randomisation's number is xored with this before it takes the sample's lane of [`pcg4d`].
pub(crate) const SOBOL_KEY: u32 = 0x50B0_1000;

/// Direction numbers of the first four Sobol dimensions, bit-reversed (least significant
/// digit in bit 31): row `k` holds bit `k`'s column of each dimension's generator matrix. From
/// Joe and Kuo's primitive polynomials and initial numbers (new-joe-kuo-6.21201): dimension 0 is
/// van der Corput's; 1 is x + 1 with m = (1); 2 is x² + x + 1 with m = (1, 3); 3 is
/// x³ + x + 1 with m = (1, 3, 1). Kept reversed because the Owen scrambling below works on
/// reversed values. `shaders/sampling.wgsl` holds the same numbers (`tests/sampler.rs`).
pub const SOBOL_DIRECTIONS: [[u32; 4]; SOBOL_BITS as usize] = sobol_directions();

const fn sobol_directions() -> [[u32; 4]; SOBOL_BITS as usize] {
    // Per dimension: the degree s, the polynomial's inner coefficients a (s - 1 bits, most
    // significant first), and the initial m_1..m_s.
    const S: [u32; 4] = [0, 1, 2, 3];
    const A: [u32; 4] = [0, 0, 1, 1];
    const M: [[u32; 3]; 4] = [[0, 0, 0], [1, 0, 0], [1, 3, 0], [1, 3, 1]];
    const N: usize = SOBOL_BITS as usize;
    let mut v = [[0u32; 4]; N];
    let mut k = 0;
    while k < N {
        v[k][0] = 1 << (31 - k);
        k += 1;
    }
    let mut d = 1;
    while d < 4 {
        let s = S[d] as usize;
        let mut k = 0;
        while k < N {
            v[k][d] = if k < s {
                M[d][k] << (31 - k)
            } else {
                // v_k = v_{k-s} ^ (v_{k-s} >> s) ^ Σ_{i=1}^{s-1} a_i v_{k-i}.
                let mut x = v[k - s][d] ^ (v[k - s][d] >> s);
                let mut i = 1;
                while i < s {
                    if (A[d] >> (s - 1 - i)) & 1 == 1 {
                        x ^= v[k - i][d];
                    }
                    i += 1;
                }
                x
            };
            k += 1;
        }
        d += 1;
    }
    let mut k = 0;
    while k < N {
        let mut d = 0;
        while d < 4 {
            v[k][d] = v[k][d].reverse_bits();
            d += 1;
        }
        k += 1;
    }
    v
}

/// Point `index` (below 2^16) of the first four Sobol dimensions, as 32-bit fractions.
pub fn sobol4(index: u32) -> [u32; 4] {
    sobol4_reversed(index.reverse_bits()).map(u32::reverse_bits)
}

/// [`sobol4`] in the reversed domain: the xor of the reversed direction numbers of the set
/// bits of the index, whose bit k is bit 31 − k of `index_reversed`.
#[inline]
fn sobol4_reversed(index_reversed: u32) -> [u32; 4] {
    let mut x = [0u32; 4];
    // The set bits only, from bit 31 down (the index has 16 bits: k < 16).
    let mut bits = index_reversed & 0xffff_0000;
    while bits != 0 {
        let k = bits.leading_zeros();
        let row = SOBOL_DIRECTIONS[k as usize];
        for d in 0..4 {
            x[d] ^= row[d];
        }
        bits &= !(0x8000_0000 >> k);
    }
    x
}

/// Owen scrambling in base 2 of a bit-reversed value, keyed by `seed`: each digit flipped or
/// not as a hash of the digits above it decides (reversed, they are the lower bits, which the
/// multiplies carry upward). The Laine-Karras construction with the constants Vegdahl found to
/// scramble every bit well ("Building a Better LK Hash", 2021; Cycles uses them too).
#[inline]
pub(crate) fn owen_reversed(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// Block `dim` of sample `sample` of `pixel` under [`SamplerKind::Sobol`], as 32-bit fractions
/// (Burley 2020, section 4: a shuffled, scrambled 4-D Sobol point).
///
/// 1. The stream and the point in it: sample i is point j = i / 2 of stream i % 2; points
///    2^16 apart fall in different randomisations.
/// 2. Seeds from the randomisation's key (pixel, randomisation, block, seed): one to shuffle
///    the points' order, one per dimension to scramble it.
/// 3. The shuffle: the point's 16 bits Owen-scrambled, so that each block of each pixel walks
///    the sequence in its own order (the first 2^m points of any shuffle are still an aligned
///    run of 2^m Sobol points) and blocks are not correlated.
/// 4. The Sobol point of the shuffled index, each dimension Owen-scrambled.
#[inline]
pub fn sobol_draw4_bits(seed: u32, pixel: u32, sample: u32, dim: u32) -> [u32; 4] {
    // Step 1 - the stream, the randomisation and the point in it.
    let (stream, point) = (sample % SOBOL_STREAMS, sample / SOBOL_STREAMS);
    let randomisation = (point >> SOBOL_BITS) * SOBOL_STREAMS + stream;
    // Step 2 - the seeds.
    let shuffle = pcg4d([pixel, randomisation ^ SOBOL_KEY, dim, seed]);
    let scramble = pcg4d(shuffle);
    // Step 3 - the shuffle, in the reversed domain: the index's 16 bits are the top 16.
    let index_reversed = owen_reversed(point.reverse_bits(), shuffle[0]) & 0xffff_0000;
    // Step 4 - the scrambled point.
    let x = sobol4_reversed(index_reversed);
    std::array::from_fn(|d| owen_reversed(x[d], scramble[d]).reverse_bits())
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

    /// Points 1 to 3 of the first four Sobol dimensions, by hand from the direction numbers.
    #[test]
    fn sobol_points_start_as_joe_and_kuo_tabulate() {
        let half = 1u32 << 31;
        assert_eq!(sobol4(0), [0; 4]);
        assert_eq!(sobol4(1), [half; 4]);
        assert_eq!(sobol4(2), [half >> 1, 3 << 30, 3 << 30, 3 << 30]);
        assert_eq!(sobol4(3), [3 << 30, 1 << 30, 1 << 30, 1 << 30]);
    }

    /// The first 2^m points of one stream of a pixel's block, however shuffled and scrambled,
    /// put exactly one point in each of the 2^m elementary boxes of every shape 2^-a x 2^-(m-a)
    /// of dimensions 0 and 1 (a (0, m, 2)-net), and one in each interval 2^-m of every
    /// dimension: the stratification the sampler is for.
    #[test]
    fn each_stream_of_a_block_is_a_net() {
        let m = 6u32;
        for (seed, pixel, dim) in [(1u32, 0u32, 0u32), (7, 4095, 3), (99, 17, 0x4000_0002)] {
            for stream in 0..SOBOL_STREAMS {
                let points: Vec<[u32; 4]> = (0..1u32 << m)
                    .map(|j| sobol_draw4_bits(seed, pixel, j * SOBOL_STREAMS + stream, dim))
                    .collect();
                for a in 0..=m {
                    let mut seen = vec![false; 1 << m];
                    for p in &points {
                        let cell = if a == 0 { 0 } else { p[0] >> (32 - a) } << (m - a)
                            | if a == m { 0 } else { p[1] >> (32 - (m - a)) };
                        assert!(
                            !seen[cell as usize],
                            "two points in one box ({a}, {})",
                            m - a
                        );
                        seen[cell as usize] = true;
                    }
                }
                for d in 0..4 {
                    let mut cells: Vec<u32> = points.iter().map(|p| p[d] >> (32 - m)).collect();
                    cells.sort_unstable();
                    cells.dedup();
                    assert_eq!(cells.len(), 1 << m, "dimension {d} not stratified");
                }
            }
        }
    }

    /// The shuffle and scramble come from (seed, pixel, sample's stream, block): each changes
    /// the numbers, and the two streams of a pixel differ.
    #[test]
    fn sobol_streams_differ_in_every_key() {
        let draw = |seed, pixel, sample, dim| {
            Sampler::of(SamplerKind::Sobol, seed, pixel, sample).draw4(dim)
        };
        let base = draw(1, 2, 6, 4);
        assert_ne!(base, draw(9, 2, 6, 4));
        assert_ne!(base, draw(1, 9, 6, 4));
        assert_ne!(base, draw(1, 2, 7, 4));
        assert_ne!(base, draw(1, 2, 8, 4));
        assert_ne!(base, draw(1, 2, 6, 9));
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
