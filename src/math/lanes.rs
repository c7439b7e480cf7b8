//! Eight values in lanes: the arithmetic of a path vertex for eight paths at once.
//!
//! The scalar shading of a path vertex is a chain of dependent square roots, divisions and hashes
//! whose latency, not its instruction count, bounds the path tracer
//! (docs/journal/2026-11-27_lanes.md). Eight independent paths side by side fill the vector units
//! instead: each function here is its scalar namesake's arithmetic, operation for operation in the
//! same order, on structure-of-arrays values of the `wide` crate's eight-lane vectors (one AVX
//! register each where the build targets AVX, as the host build does; two SSE2 halves in the
//! portable build). No operation is fused or reordered, so every lane's result is the scalar
//! function's bit for bit (the tests below, on values that include zeros of both signs, subnormals,
//! infinities and NaN where the scalar functions accept them). The compiler's own vectorisation of
//! plain loops over arrays leaves most of this work scalar.

use crate::math::sampling::SamplerKind;
use glam::Vec3;
use std::f32::consts::FRAC_PI_2;
use wide::{f32x8, i32x8, u32x8};

/// The number of lanes.
pub const LANES: usize = 8;

/// Eight floats.
pub type F8 = f32x8;
/// Eight unsigned integers.
pub type U8 = u32x8;

/// The sign bit in every lane: `x ^ SIGN` is −x, exactly as Rust's unary minus (a flip of
/// the sign bit, −0 from +0 included).
const SIGN: f32x8 = f32x8::splat(-0.0);

/// −x in every lane (Rust's unary minus: the sign bit flipped).
#[inline(always)]
pub fn neg(x: F8) -> F8 {
    x ^ SIGN
}

/// A float mask as integer lanes.
#[inline(always)]
fn bits(x: f32x8) -> u32x8 {
    bytemuck::cast(x)
}

/// Eight lanes of `f(l)`.
#[inline(always)]
pub fn floats(f: impl Fn(usize) -> f32) -> F8 {
    let mut out = [0.0; LANES];
    for (l, o) in out.iter_mut().enumerate() {
        *o = f(l);
    }
    f32x8::new(out)
}

/// Eight lanes of `f(l)`.
#[inline(always)]
pub fn uints(f: impl Fn(usize) -> u32) -> U8 {
    let mut out = [0; LANES];
    for (l, o) in out.iter_mut().enumerate() {
        *o = f(l);
    }
    u32x8::new(out)
}

/// Eight 3-vectors as three rows of eight coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct V8 {
    pub x: F8,
    pub y: F8,
    pub z: F8,
}

impl V8 {
    /// The vectors `v(l)` in lanes.
    #[inline(always)]
    pub fn gather(v: impl Fn(usize) -> Vec3) -> V8 {
        let (mut x, mut y, mut z) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
        for l in 0..LANES {
            let w = v(l);
            (x[l], y[l], z[l]) = (w.x, w.y, w.z);
        }
        V8 {
            x: f32x8::new(x),
            y: f32x8::new(y),
            z: f32x8::new(z),
        }
    }

    /// The 3-vectors at float `offset` of records `index[l]` of `records` (a `Pod` record of
    /// whole floats or integers, as the scene's tables are), one per lane: with AVX2's gather
    /// instruction where the build has it, three loads for the eight lanes, else lane by lane.
    /// The values are loaded, not computed, so both ways give the same bits.
    ///
    /// # Panics
    /// If an index is past the records, or the offset past a record.
    #[inline(always)]
    pub fn gather_from<T: bytemuck::Pod>(records: &[T], index: U8, offset: usize) -> V8 {
        let stride = std::mem::size_of::<T>() / 4;
        assert!(std::mem::size_of::<T>().is_multiple_of(4) && offset + 3 <= stride);
        assert!(index.reduce_max() < records.len() as u32);
        let floats: &[f32] = bytemuck::cast_slice(records);
        #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
        {
            use std::arch::x86_64::{__m256, __m256i, _mm256_i32gather_ps};
            assert!(floats.len() <= i32::MAX as usize);
            let at: __m256i =
                bytemuck::cast(index * u32x8::splat(stride as u32) + u32x8::splat(offset as u32));
            let row = |k: usize| -> f32x8 {
                // SAFETY: the build has AVX2; every lane's index (below records.len() times
                // the stride, plus at most stride - 1) lies within `floats` (checked above).
                let v: __m256 = unsafe { _mm256_i32gather_ps::<4>(floats.as_ptr().add(k), at) };
                bytemuck::cast(v)
            };
            V8 {
                x: row(0),
                y: row(1),
                z: row(2),
            }
        }
        #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
        {
            let index = index.to_array();
            V8::gather(|l| {
                let at = index[l] as usize * stride + offset;
                Vec3::new(floats[at], floats[at + 1], floats[at + 2])
            })
        }
    }

    /// The lanes as eight vectors.
    #[inline(always)]
    pub fn lanes(&self) -> [Vec3; LANES] {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        let mut out = [Vec3::ZERO; LANES];
        for l in 0..LANES {
            out[l] = Vec3::new(x[l], y[l], z[l]);
        }
        out
    }

    #[inline(always)]
    pub fn add(&self, o: &V8) -> V8 {
        V8 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }

    #[inline(always)]
    pub fn sub(&self, o: &V8) -> V8 {
        V8 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }

    /// Coordinate by coordinate (glam's `Vec3 * Vec3`).
    #[inline(always)]
    pub fn mul(&self, o: &V8) -> V8 {
        V8 {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }

    /// Each lane's vector times that lane's scalar (glam's `f32 * Vec3`, `Vec3 * f32`).
    #[inline(always)]
    pub fn scale(&self, s: F8) -> V8 {
        V8 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }

    /// Each lane's vector divided by that lane's scalar (glam's `Vec3 / f32`).
    #[inline(always)]
    pub fn div(&self, s: F8) -> V8 {
        V8 {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }

    /// Negated in the lanes of `mask` (glam's `-v`, chosen per lane).
    #[inline(always)]
    pub fn neg_where(&self, mask: F8) -> V8 {
        let flip = mask & SIGN;
        V8 {
            x: self.x ^ flip,
            y: self.y ^ flip,
            z: self.z ^ flip,
        }
    }

    /// −v in every lane.
    #[inline(always)]
    pub fn neg(&self) -> V8 {
        V8 {
            x: neg(self.x),
            y: neg(self.y),
            z: neg(self.z),
        }
    }

    #[inline(always)]
    pub fn abs(&self) -> V8 {
        V8 {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }

    /// glam's `Vec3::dot`: (x·x') + (y·y') + (z·z'), added left to right.
    #[inline(always)]
    pub fn dot(&self, o: &V8) -> F8 {
        (self.x * o.x) + (self.y * o.y) + (self.z * o.z)
    }

    /// glam's `Vec3::max_element`: max(max(x, y), z), each max `if a > b { a } else { b }`
    /// (so a NaN compared loses to the other operand on the right, as there).
    #[inline(always)]
    pub fn max_element(&self) -> F8 {
        let max = |a: F8, b: F8| a.simd_gt(b).select(a, b);
        max(max(self.x, self.y), self.z)
    }

    /// `if_true` in the lanes of `mask`, `self` in the others.
    #[inline(always)]
    pub fn select_where(&self, mask: F8, if_true: &V8) -> V8 {
        V8 {
            x: mask.select(if_true.x, self.x),
            y: mask.select(if_true.y, self.y),
            z: mask.select(if_true.z, self.z),
        }
    }

    /// Lane `l` as a vector.
    #[inline(always)]
    pub fn lane(&self, l: usize) -> Vec3 {
        Vec3::new(
            self.x.as_array()[l],
            self.y.as_array()[l],
            self.z.as_array()[l],
        )
    }

    /// Lane `l` set to `v`.
    #[inline(always)]
    pub fn set_lane(&mut self, l: usize, v: Vec3) {
        self.x.as_mut_array()[l] = v.x;
        self.y.as_mut_array()[l] = v.y;
        self.z.as_mut_array()[l] = v.z;
    }
}

/// [`crate::math::geometry::triangle_point`] in lanes: the point of the triangles of corners `p0`,
/// `p1`, `p2` at barycentrics (1 - b1 - b2, `b1`, `b2`), b0 p0 + b1 p1 + b2 p2, and its error
/// bound gamma(7) (|b0 p0| + |b1 p1| + |b2 p2|).
#[inline(always)]
pub fn triangle_point(p0: &V8, p1: &V8, p2: &V8, b1: F8, b2: F8) -> (V8, V8) {
    let b0 = f32x8::splat(1.0) - b1 - b2;
    let (w0, w1, w2) = (p0.scale(b0), p1.scale(b1), p2.scale(b2));
    let p = w0.add(&w1).add(&w2);
    let p_err = w0
        .abs()
        .add(&w1.abs())
        .add(&w2.abs())
        .scale(f32x8::splat(crate::math::geometry::gamma(7)));
    (p, p_err)
}

/// [`crate::math::geometry::triangle_hit_point`] in lanes, for the triangles of corners `p0`, `p1`,
/// `p2` and unit normals `n` at barycentrics (`b1`, `b2`): the point and its error bound, and
/// the mask of the lanes where that is the scalar function's result, the point lying at least
/// its margin from every edge (or the triangle being degenerate). In the other lanes the scalar
/// function moves the point inward; they are left to it.
#[inline(always)]
pub fn triangle_hit_point(p0: &V8, p1: &V8, p2: &V8, n: &V8, b1: F8, b2: F8) -> (V8, V8, F8) {
    let (p, p_err) = triangle_point(p0, p1, p2, b1, b2);
    let b0 = f32x8::splat(1.0) - b1 - b2;
    // The edges' margins: 2A = ((p1 - p0) x (p2 - p0)) . n, m = 2 |p_err|_1
    let (e1, e2) = (p1.sub(p0), p2.sub(p0));
    let cross = V8 {
        x: e1.y * e2.z - e2.y * e1.z,
        y: e1.z * e2.x - e2.z * e1.x,
        z: e1.x * e2.y - e2.x * e1.y,
    };
    let two_area = cross.dot(n);
    let margin = f32x8::splat(2.0) * (p_err.x + p_err.y + p_err.z);
    let length = |v: &V8| v.dot(v).sqrt();
    let per_area = margin / two_area;
    let least = [length(&p2.sub(p1)), length(&e2), length(&e1)].map(|e| e * per_area);
    let inside = b0.simd_ge(least[0]) & b1.simd_ge(least[1]) & b2.simd_ge(least[2]);
    (p, p_err, inside | !two_area.simd_gt(f32x8::ZERO))
}

/// The lanes whose bits are set in `bits`, lowest first.
#[inline]
pub fn lanes_of(mut bits: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        let l = bits.trailing_zeros() as usize;
        bits &= bits.wrapping_sub(1);
        (l < LANES).then_some(l)
    })
}

/// The float mask (all bits set, or none) of the lanes whose bits are set in `bits`.
#[inline(always)]
pub fn mask(bits: u32) -> F8 {
    let lane_bits = u32x8::new([1, 2, 4, 8, 16, 32, 64, 128]);
    bytemuck::cast((u32x8::splat(bits) & lane_bits).simd_eq(lane_bits))
}

/// [`crate::math::sampling::Sampler::draw4`] in lanes: block `dim` of the streams (`pixel`,
/// `sample`, `seed`) of `kind`, as four rows of eight numbers.
#[inline(always)]
pub fn draw4(kind: SamplerKind, seed: u32, pixel: U8, sample: U8, dim: U8) -> [F8; 4] {
    let v = match kind {
        SamplerKind::Independent => pcg4d([pixel, sample, dim, u32x8::splat(seed)]),
        SamplerKind::Sobol => sobol_draw4_bits(seed, pixel, sample, dim),
    };
    // (x >> 8) < 2^24 converts exactly through i32, as `u32_to_unit_f32` converts it.
    v.map(|row| {
        let top: i32x8 = bytemuck::cast(row.unbounded_shr_scalar(8));
        f32x8::from_i32x8(top) * f32x8::splat(1.0 / 16_777_216.0)
    })
}

/// [`crate::math::sampling::sobol_draw4_bits`] in lanes, step for step (the Sobol generator
/// over all 16 bits, masked, where the scalar one skips the clear bits: the same xors).
#[inline(always)]
fn sobol_draw4_bits(seed: u32, pixel: U8, sample: U8, dim: U8) -> [U8; 4] {
    use crate::math::sampling::{SOBOL_BITS, SOBOL_DIRECTIONS, SOBOL_KEY};
    let splat = u32x8::splat;
    // Step 1 - the stream, the randomisation and the point in it (two streams).
    let (stream, point) = (sample & splat(1), sample >> 1);
    let randomisation = ((point >> SOBOL_BITS) << 1) + stream;
    // Step 2 - the seeds.
    let shuffle = pcg4d([pixel, randomisation ^ splat(SOBOL_KEY), dim, splat(seed)]);
    let scramble = pcg4d(shuffle);
    // Step 3 - the shuffle, in the reversed domain.
    let index_reversed = owen_reversed(reverse_bits(point), shuffle[0]) & splat(0xffff_0000);
    // Step 4 - the scrambled point.
    let mut x = [u32x8::ZERO; 4];
    for (k, row) in SOBOL_DIRECTIONS.iter().enumerate() {
        let take = u32x8::ZERO - ((index_reversed >> (31 - k as u32)) & splat(1));
        for d in 0..4 {
            x[d] ^= splat(row[d]) & take;
        }
    }
    std::array::from_fn(|d| reverse_bits(owen_reversed(x[d], scramble[d])))
}

/// [`crate::math::sampling::owen_reversed`] in lanes.
#[inline(always)]
fn owen_reversed(x: U8, seed: U8) -> U8 {
    let splat = u32x8::splat;
    let mut x = x ^ (x * splat(0x3d20_adea));
    x += seed;
    x *= (seed >> 16) | splat(1);
    x ^= x * splat(0x0552_6c56);
    x ^ (x * splat(0x53a2_2864))
}

/// `u32::reverse_bits` in lanes: adjacent bits, pairs, nibbles, bytes and halves swapped.
#[inline(always)]
fn reverse_bits(x: U8) -> U8 {
    let swap = |x: U8, mask: u32, k: u32| {
        ((x >> k) & u32x8::splat(mask)) | ((x & u32x8::splat(mask)) << k)
    };
    let x = swap(x, 0x5555_5555, 1);
    let x = swap(x, 0x3333_3333, 2);
    let x = swap(x, 0x0f0f_0f0f, 4);
    let x = swap(x, 0x00ff_00ff, 8);
    (x >> 16) | (x << 16)
}

/// [`crate::math::sampling::pcg4d`] in lanes: row k holds the k-th input (and output) of each lane.
#[inline(always)]
fn pcg4d(v: [U8; 4]) -> [U8; 4] {
    let (a, c) = (u32x8::splat(1_664_525), u32x8::splat(1_013_904_223));
    let mut v = v.map(|x| x * a + c);
    let round = |v: &mut [U8; 4]| {
        v[0] += v[1] * v[3];
        v[1] += v[2] * v[0];
        v[2] += v[0] * v[1];
        v[3] += v[1] * v[2];
    };
    round(&mut v);
    v = v.map(|x| x ^ x.unbounded_shr_scalar(16));
    round(&mut v);
    v
}

/// [`crate::math::sampling::sin_cos_turns`] in lanes: (sin 2πu, cos 2πu).
#[inline(always)]
pub fn sin_cos_turns(u: F8) -> (F8, F8) {
    let splat = f32x8::splat;
    let q = (u * splat(4.0) + splat(0.5)).floor();
    let x = (u * splat(4.0) - q) * splat(FRAC_PI_2);
    let x2 = x * x;
    let s = x + x
        * x2
        * (splat(-1.666_665_5e-1) + x2 * (splat(8.332_161e-3) + x2 * splat(-1.951_529_6e-4)));
    let c = splat(1.0) - splat(0.5) * x2
        + x2 * x2
            * (splat(4.166_664_6e-2) + x2 * (splat(-1.388_731_6e-3) + x2 * splat(2.443_315_7e-5)));
    // Quarter turn q: (s, c), (c, −s), (−s, −c), (−c, s).
    let quarter = q.trunc_int() & i32x8::splat(3);
    let odd: f32x8 = bytemuck::cast((quarter & i32x8::splat(1)).simd_eq(i32x8::splat(1)));
    let half: f32x8 = bytemuck::cast((quarter & i32x8::splat(2)).simd_eq(i32x8::splat(2)));
    let flip = half & SIGN;
    let sin = odd.select(c, s) ^ flip;
    let cos = odd.select(neg(s), c) ^ flip;
    (sin, cos)
}

/// [`crate::math::sampling::sample_cosine_hemisphere`] in lanes.
#[inline(always)]
pub fn sample_cosine_hemisphere(u1: F8, u2: F8) -> V8 {
    let r = u1.sqrt();
    let (sin_phi, cos_phi) = sin_cos_turns(u2);
    V8 {
        x: r * cos_phi,
        y: r * sin_phi,
        z: (f32x8::splat(1.0) - u1).max(f32x8::ZERO).sqrt(),
    }
}

/// [`crate::math::sampling::orthonormal_basis`] in lanes.
#[inline(always)]
pub fn orthonormal_basis(n: &V8) -> (V8, V8) {
    let one = f32x8::splat(1.0);
    let sign = n.z.simd_ge(f32x8::ZERO).select(one, -one);
    let a = f32x8::splat(-1.0) / (sign + n.z);
    let b = n.x * n.y * a;
    let t = V8 {
        x: one + sign * n.x * n.x * a,
        y: sign * b,
        z: neg(sign) * n.x,
    };
    let bt = V8 {
        x: b,
        y: sign + n.y * n.y * a,
        z: neg(n.y),
    };
    (t, bt)
}

/// [`crate::math::geometry::offset_ray_origin`] in lanes.
#[inline(always)]
pub fn offset_ray_origin(p: &V8, p_err: &V8, n: &V8, w: &V8) -> V8 {
    let d = n.abs().dot(p_err);
    let offset = n.scale(d).neg_where(w.dot(n).simd_lt(f32x8::ZERO));
    step_away(&p.add(&offset), &offset)
}

/// [`crate::math::geometry::step_away_scalar`] in lanes: each coordinate stepped one ulp the way
/// its offset points, unchanged where the offset is 0 or NaN or the step would leave an infinity
/// (the masks of [`crate::math::geometry::step_away`], eight lanes wide).
#[inline(always)]
pub fn step_away(po: &V8, offset: &V8) -> V8 {
    V8 {
        x: step_away_row(po.x, offset.x),
        y: step_away_row(po.y, offset.y),
        z: step_away_row(po.z, offset.z),
    }
}

#[inline(always)]
fn step_away_row(x: F8, s: F8) -> F8 {
    let zero = f32x8::ZERO;
    let up = bits(s.simd_gt(zero));
    let down = bits(s.simd_lt(zero));
    let x_bits = bits(x);
    // ±0 steps from the bits of +0 (up) or −0 (down), as next_float_up/down take them.
    let is_zero = bits(x.simd_eq(zero));
    let zero_bits = down & u32x8::splat(0x8000_0000);
    let base = (is_zero & zero_bits) | (!is_zero & x_bits);
    // Up: +1 where x ≥ 0 (false for NaN), else −1; down: −1 where x > 0, else +1.
    let (one, minus_one) = (u32x8::splat(1), u32x8::splat(u32::MAX));
    let ge = bits(x.simd_ge(zero));
    let gt = bits(x.simd_gt(zero));
    let delta_up = (ge & one) | (!ge & minus_one);
    let delta_down = (gt & minus_one) | (!gt & one);
    let delta = (up & delta_up) | (!up & delta_down);
    let stepped = base + delta;
    // Unchanged: offset 0 or NaN, or the infinity the step points to.
    let at_inf = (up & bits(x.simd_eq(f32x8::splat(f32::INFINITY))))
        | (down & bits(x.simd_eq(f32x8::splat(f32::NEG_INFINITY))));
    let moves = !at_inf & (up | down);
    bytemuck::cast((moves & stepped) | (!moves & x_bits))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::geometry::{offset_ray_origin as offset_scalar, step_away_scalar};
    use crate::math::sampling::{self, u32_to_unit_f32, Sampler};

    fn draw4_scalar(kind: SamplerKind, seed: u32, pixel: u32, sample: u32, dim: u32) -> [f32; 4] {
        Sampler::of(kind, seed, pixel, sample).draw4(dim)
    }

    fn lanes_of(values: &[f32], start: usize) -> F8 {
        floats(|l| values[(start + l) % values.len()])
    }

    #[test]
    fn draw4_in_lanes_is_the_samplers_draw4() {
        for (k, kind) in (0..64u32)
            .flat_map(|k| [SamplerKind::Independent, SamplerKind::Sobol].map(|kind| (k, kind)))
        {
            let (pixel, sample, dim) = (
                uints(|l| k * 977 + l as u32 * 131),
                uints(|l| k * 3 + l as u32),
                uints(|l| (k + l as u32) % 41),
            );
            let rows = draw4(kind, k.wrapping_mul(2_654_435_761), pixel, sample, dim)
                .map(|r| r.to_array());
            let (pixel, sample, dim) = (pixel.to_array(), sample.to_array(), dim.to_array());
            for l in 0..LANES {
                let want = draw4_scalar(
                    kind,
                    k.wrapping_mul(2_654_435_761),
                    pixel[l],
                    sample[l],
                    dim[l],
                );
                let got = [rows[0][l], rows[1][l], rows[2][l], rows[3][l]];
                assert_eq!(got.map(f32::to_bits), want.map(f32::to_bits));
            }
        }
    }

    #[test]
    fn sampling_in_lanes_is_the_scalar_sampling_bit_for_bit() {
        // Every quarter turn's edges, and a sweep over [0, 1).
        let mut u: Vec<f32> = vec![0.0, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875];
        u.extend([
            1.0 - f32::EPSILON / 2.0,
            0.249_999_98,
            0.250_000_03,
            1e-30,
            1e-40,
        ]);
        u.extend((0..4096).map(|i| u32_to_unit_f32((i as u32).wrapping_mul(2_654_435_761))));
        for start in (0..u.len()).step_by(3) {
            let (a, b) = (lanes_of(&u, start), lanes_of(&u, start + 5));
            let (sin, cos) = sin_cos_turns(a);
            let (sin, cos) = (sin.to_array(), cos.to_array());
            let dir = sample_cosine_hemisphere(a, b).lanes();
            let (a, b) = (a.to_array(), b.to_array());
            for l in 0..LANES {
                let (s, c) = sampling::sin_cos_turns(a[l]);
                assert_eq!(
                    (sin[l].to_bits(), cos[l].to_bits()),
                    (s.to_bits(), c.to_bits())
                );
                let want = sampling::sample_cosine_hemisphere(a[l], b[l]);
                assert_eq!(
                    dir[l].to_array().map(f32::to_bits),
                    want.to_array().map(f32::to_bits)
                );
            }
        }
    }

    /// Unit normals from every octant, the poles included, and their bases.
    #[test]
    fn bases_and_offsets_in_lanes_are_the_scalar_ones_bit_for_bit() {
        let mut normals = vec![
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            -Vec3::Y,
            Vec3::new(0.0, 0.0, -0.0),
        ];
        for i in 0..200u32 {
            let u = u32_to_unit_f32(i.wrapping_mul(2_654_435_761));
            let v = u32_to_unit_f32(i.wrapping_mul(40_503).wrapping_add(7));
            let z = 1.0 - 2.0 * u;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let (s, c) = sampling::sin_cos_turns(v);
            normals.push(Vec3::new(r * c, r * s, z));
        }
        let specials = [
            0.0,
            -0.0,
            1e-40,
            -1e-40,
            3.5,
            -2.25,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        for start in 0..normals.len() {
            let n = V8::gather(|l| normals[(start + l) % normals.len()]);
            let w = V8::gather(|l| normals[(start + 3 * l + 1) % normals.len()]);
            let p = V8::gather(|l| {
                Vec3::new(
                    specials[(start + l) % 8],
                    specials[(start + 2 * l + 1) % 8],
                    0.1 * (start as f32) - 7.0,
                )
            });
            let p_err = V8::gather(|l| Vec3::splat(1e-6 * (l as f32)));
            let (t, b) = orthonormal_basis(&n);
            let (t, b) = (t.lanes(), b.lanes());
            let o = offset_ray_origin(&p, &p_err, &n, &w).lanes();
            // Offsets of every sign, zeros of both signs and NaN among them.
            let offset = V8::gather(|l| {
                let k = start + l;
                Vec3::new(
                    specials[k % 8],
                    [0.0, -0.0, f32::NAN, 1.0][k % 4],
                    -specials[(k + 3) % 8],
                )
            });
            let stepped = step_away(&p, &offset).lanes();
            let offset = offset.lanes();
            let (n, w, p, p_err) = (n.lanes(), w.lanes(), p.lanes(), p_err.lanes());
            for l in 0..LANES {
                let (tw, bw) = sampling::orthonormal_basis(n[l]);
                let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                assert_eq!((bits(t[l]), bits(b[l])), (bits(tw), bits(bw)));
                let want = offset_scalar(p[l], p_err[l], n[l], w[l]);
                assert_eq!(bits(o[l]), bits(want));
                assert_eq!(bits(stepped[l]), bits(step_away_scalar(p[l], offset[l])));
            }
        }
    }

    /// Triangles of every shape (slivers, a degenerate one, one far from the origin, both
    /// windings) hit at barycentrics inside, on and beside every edge and corner: in every lane
    /// the mask says whether `triangle_hit_point` keeps the point, and where it does the point
    /// and its bound are the scalar ones bit for bit. Both outcomes occur.
    #[test]
    fn triangle_hit_points_in_lanes_are_the_scalar_ones_where_kept() {
        use crate::layout::Triangle;
        use crate::math::geometry::{triangle_hit_point as scalar, triangle_point as unmoved};
        let mut triangles = vec![
            Triangle::new([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0),
            Triangle::new([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], 0),
            Triangle::new([0.0, 0.0, 0.0], [1e3, 0.0, 0.0], [0.0, 1e-4, 0.0], 0),
            Triangle::new([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0], 0),
            Triangle::new(
                [1e5, -2e5, 3e4],
                [1e5 + 3.0, -2e5, 3e4],
                [1e5, -2e5 + 2.0, 3e4 + 1.0],
                0,
            ),
        ];
        for i in 0..40u32 {
            let u = |k: u32| u32_to_unit_f32(sampling::pcg4d([i, k, 5, 6])[0]) * 10.0 - 5.0;
            triangles.push(Triangle::new(
                [u(0), u(1), u(2)],
                [u(3), u(4), u(5)],
                [u(6), u(7), u(8)],
                0,
            ));
        }
        let edge = [0.0, 1e-7, 1e-5, 0.25, 0.5, 1.0 - 1e-6, 1.0];
        let (mut kept, mut moved) = (0, 0);
        for (i, tri) in triangles.iter().enumerate() {
            for (j, &b1) in edge.iter().enumerate() {
                let b2s = floats(|l| edge[(j + l) % edge.len()] * (1.0 - b1));
                let corner = |v: [f32; 3]| V8::gather(|_| Vec3::from(v));
                let b1s = F8::splat(b1);
                let (p, p_err, keep) = triangle_hit_point(
                    &corner(tri.v0),
                    &corner(tri.v1),
                    &corner(tri.v2),
                    &corner(tri.n),
                    b1s,
                    b2s,
                );
                let (p, p_err, keep) = (p.lanes(), p_err.lanes(), keep.to_bitmask());
                for l in 0..LANES {
                    let b2 = b2s.as_array()[l];
                    let (want, want_err) = scalar(tri, b1, b2);
                    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                    if keep & (1 << l) != 0 {
                        kept += 1;
                        assert_eq!(bits(p[l]), bits(want), "triangle {i}, ({b1}, {b2})");
                        assert_eq!(bits(p_err[l]), bits(want_err), "triangle {i}, ({b1}, {b2})");
                        assert_eq!(bits(want), bits(unmoved(tri, b1, b2).0));
                    } else {
                        moved += 1;
                    }
                }
            }
        }
        assert!(kept > 500 && moved > 100, "{kept} kept, {moved} moved");
    }

    /// `gather_from` loads lane l's 3-vector from record `index[l]` at the offset, the last
    /// record and repeated indices included, as reading the record does.
    #[test]
    fn gather_from_loads_each_lanes_record() {
        use crate::layout::Triangle;
        let triangles: Vec<Triangle> = (0..13)
            .map(|i| {
                let f = i as f32;
                Triangle::new(
                    [f, f + 0.5, -f],
                    [2.0 * f, 3.0, f * f],
                    [-1.0, f, 0.25 * f],
                    i,
                )
            })
            .collect();
        for start in 0..13u32 {
            let index = uints(|l| (start + 5 * l as u32) % 13);
            for (offset, field) in [(0, 0), (4, 1), (8, 2), (12, 3)] {
                let got = V8::gather_from(&triangles, index, offset).lanes();
                for l in 0..LANES {
                    let t = &triangles[index.as_array()[l] as usize];
                    let want = [t.v0, t.v1, t.v2, t.n][field];
                    assert_eq!(got[l].to_array(), want, "record {}", index.as_array()[l]);
                }
            }
        }
    }
}
