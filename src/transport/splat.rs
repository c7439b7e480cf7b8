//! Order-independent sums of splats: what light subpaths add to the pixels they are seen in.
//!
//! A light subpath can land in any pixel, so many threads add to one pixel at once. Float
//! addition is not associative, and core WGSL has no float atomics, so each splat is rounded
//! once to a 64-bit fixed-point number (`FRACTION_BITS` bits after the point) and added as an
//! integer: the sum is then exactly the same whatever order the splats arrive in, on either
//! backend. `shaders/splat.wgsl` keeps each 64-bit sum in two `atomic<u32>` words with a carry;
//! this side keeps it in an `AtomicU64`. Both round the same f32 to the same integer
//! (round-half-even of v·2^24, exact in f32), so the same splats give the same sums bit for bit.
//!
//! A sum that would pass 2^64 (2^40 ≈ 1.1e12 in value), and a splat that is negative, NaN or
//! infinite, is not added: it sets the cell's overflow flag, and the pixel's value for the
//! iteration is then counted as dropped, never used.

use glam::Vec3;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

/// Bits after the binary point: a resolution of 6e-8, and values up to 2^40.
pub const FRACTION_BITS: u32 = 24;
/// 2^FRACTION_BITS as f32 (exact).
pub const SCALE: f32 = (1u64 << FRACTION_BITS) as f32;

/// `v` as fixed point: round(v · 2^24), ties to even, or None where that is not a u64 (v
/// negative, NaN, infinite or 2^40 and more). v · 2^24 is exact (a power of two), and rounding
/// an f32 to an integer is exact, so `shaders/splat.wgsl` computes the same integer.
#[inline]
pub fn to_fixed(v: f32) -> Option<u64> {
    let r = (v * SCALE).round_ties_even();
    // 2^64 as f32 is exact; NaN is in no range.
    if (0.0..18_446_744_073_709_551_616.0).contains(&r) {
        Some(r as u64)
    } else {
        None
    }
}

/// A fixed-point sum back to a value.
#[inline]
pub fn from_fixed(x: u64) -> f64 {
    x as f64 / SCALE as f64
}

/// One pixel's splat sums for the current iteration, and whether any of them overflowed.
#[derive(Debug, Default)]
pub struct SplatCell {
    pub rgb: [AtomicU64; 3],
    pub overflow: AtomicU32,
}

/// The splat film of one iteration: one cell per pixel, added to by any thread.
#[derive(Debug)]
pub struct Splats {
    pub width: u32,
    pub height: u32,
    cells: Vec<SplatCell>,
}

impl Splats {
    pub fn new(width: u32, height: u32) -> Splats {
        Splats {
            width,
            height,
            cells: (0..width as usize * height as usize)
                .map(|_| SplatCell::default())
                .collect(),
        }
    }

    /// Adds `rgb` to pixel `index`, order-independently: each channel's fixed-point value is
    /// added with one atomic add; a value that cannot be added, or a sum that wraps, sets the
    /// pixel's overflow flag instead (`splat_add` in `shaders/splat.wgsl`).
    #[inline]
    pub fn add(&self, index: usize, rgb: Vec3) {
        let cell = &self.cells[index];
        for c in 0..3 {
            match to_fixed(rgb[c]) {
                Some(0) => {}
                Some(x) => {
                    let old = cell.rgb[c].fetch_add(x, Ordering::Relaxed);
                    if old.checked_add(x).is_none() {
                        cell.overflow.store(1, Ordering::Relaxed);
                    }
                }
                None => cell.overflow.store(1, Ordering::Relaxed),
            }
        }
    }

    /// Pixel `index`'s sum, or None if it overflowed; the cell is cleared for the next
    /// iteration (`splat_take` in `shaders/splat.wgsl`). Called by the one thread that owns the
    /// pixel after every splat of the iteration has landed.
    #[inline]
    pub fn take(&self, index: usize) -> Option<Vec3> {
        let cell = &self.cells[index];
        let rgb = [0, 1, 2].map(|c| from_fixed(cell.rgb[c].swap(0, Ordering::Relaxed)) as f32);
        let overflow = cell.overflow.swap(0, Ordering::Relaxed) != 0;
        (!overflow).then(|| Vec3::from(rgb))
    }

    /// Every cell cleared: what an iteration stopped before its end leaves is dropped.
    pub fn clear(&self) {
        for cell in &self.cells {
            for c in &cell.rgb {
                c.store(0, Ordering::Relaxed);
            }
            cell.overflow.store(0, Ordering::Relaxed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_rounds_to_nearest_and_refuses_what_it_cannot_hold() {
        assert_eq!(to_fixed(0.0), Some(0));
        assert_eq!(to_fixed(1.0), Some(1 << 24));
        // Half a unit rounds to even: 0.5 · 2^-24 -> 0, 1.5 · 2^-24 -> 2.
        assert_eq!(to_fixed(0.5 / SCALE), Some(0));
        assert_eq!(to_fixed(1.5 / SCALE), Some(2));
        assert_eq!(to_fixed(-1e-30), Some(0));
        assert_eq!(to_fixed(-1.0), None);
        assert_eq!(to_fixed(f32::NAN), None);
        assert_eq!(to_fixed(f32::INFINITY), None);
        assert_eq!(to_fixed(2f32.powi(40)), None);
        assert!(to_fixed(2f32.powi(39)).is_some());
    }

    /// The same splats in two different orders (and from several threads) give the same sums
    /// bit for bit, where f32 addition in those orders does not.
    #[test]
    fn splat_sums_do_not_depend_on_the_order_of_the_splats() {
        let values: Vec<f32> = (0..10_000u32)
            .map(|i| {
                let u = crate::math::sampling::Sampler::new(3, i, 0).draw4(0);
                u[0] * 10f32.powf(6.0 * u[1] - 4.0)
            })
            .collect();
        let forward = Splats::new(1, 1);
        for &v in &values {
            forward.add(0, Vec3::splat(v));
        }
        let backward = Splats::new(1, 1);
        for &v in values.iter().rev() {
            backward.add(0, Vec3::splat(v));
        }
        let threaded = Splats::new(1, 1);
        std::thread::scope(|s| {
            for chunk in values.chunks(1000) {
                let t = &threaded;
                s.spawn(move || chunk.iter().for_each(|&v| t.add(0, Vec3::splat(v))));
            }
        });
        let a = forward.take(0).unwrap();
        assert_eq!(a, backward.take(0).unwrap());
        assert_eq!(a, threaded.take(0).unwrap());
        let f32_forward: f32 = values.iter().sum();
        let f32_backward: f32 = values.iter().rev().sum();
        assert_ne!(
            f32_forward, f32_backward,
            "the check needs an order-dependent f32 sum"
        );
        // And the fixed-point sum is the f64 sum to within the rounding of 10^4 splats.
        let exact: f64 = values.iter().map(|&v| v as f64).sum();
        assert!((a.x as f64 - exact).abs() < 1e-6 * exact + 1e4 / SCALE as f64);
    }

    #[test]
    fn an_overflowing_sum_is_flagged_not_wrapped() {
        let s = Splats::new(2, 1);
        for _ in 0..3 {
            s.add(0, Vec3::new(1.0, 2f32.powi(39), 0.0));
        }
        assert_eq!(s.take(0), None, "3 · 2^39 passes 2^40");
        s.add(1, Vec3::new(1.0, f32::NAN, 0.0));
        assert_eq!(s.take(1), None);
        // Taking clears the cell and its flag.
        s.add(0, Vec3::ONE);
        assert_eq!(s.take(0), Some(Vec3::ONE));
    }
}
