//! A hashed uniform grid over an iteration's light vertices, for the range queries of photon
//! merging (`--method sppm|vcm`): every vertex within the merge radius r of a point.
//!
//! Cells are cubes of side 2r, so the ball of radius r about any point lies in the 2x2x2 block
//! of cells nearest to it (per axis, the point's cell and the neighbour on the side of the
//! nearer face). Cells are hashed into a power-of-two number of buckets, at least as many as
//! vertices, and the vertices are sorted by bucket with a counting sort: count per bucket, an
//! exclusive prefix sum, a scatter in vertex order. So the layout is a function of the vertices
//! alone: bucket b holds `entries[starts[b]..starts[b + 1]]`, in increasing vertex index, each
//! entry the vertex's position and index in one vec4 (the index's bits in w), so that a query
//! reads its buckets' positions contiguously and loads only the vertices within r (the GPU by
//! index; the CPU reads a copy of what a merge needs, kept in entry order and named by the
//! entry's slot: `transport::subpath::PhotonRecord`, [`HashGrid::finish_query_slots`]).
//! `shaders/hash_grid.wgsl` builds the same arrays with atomics and a scan dispatch and then
//! sorts each bucket, so both backends hold the same grid bit for bit.
//!
//! Two of the eight cells may hash to one bucket; a query visits each bucket once, and tests
//! every vertex in it against the exact distance, so collisions cost time, never correctness.

use glam::{IVec3, Vec3};
use rayon::prelude::*;

/// Cell coordinates are clamped to ±2^30 before hashing, so a radius tiny against the scene
/// cannot overflow an i32 (the same clamp on both backends).
const CELL_LIMIT: f32 = 1_073_741_824.0;

/// The slack, in cell units, by which a query takes a neighbouring cell that its ball only
/// nearly reaches (`GridParams::query_buckets`): 2^-10, so that a vertex on the ball's rim that
/// rounding puts across the face is still found.
pub const QUERY_MARGIN: f32 = 1.0 / 1024.0;

/// The hash of a cell, SmallVCM's and Teschner et al.'s (2003) three large primes, in wrapping
/// u32 arithmetic (as WGSL computes it).
#[inline]
pub fn hash_cell(c: IVec3) -> u32 {
    (c.x as u32).wrapping_mul(73_856_093)
        ^ (c.y as u32).wrapping_mul(19_349_663)
        ^ (c.z as u32).wrapping_mul(83_492_791)
}

/// The grid's constants, in the layout of `shaders/hash_grid.wgsl` (`GridParams`).
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GridParams {
    /// The origin of the cells: the scene's bounding-box corner.
    pub min: [f32; 3],
    /// 1 / cell size = 1 / (2 r).
    pub inv_cell: f32,
    /// Buckets - 1 (a power of two minus one).
    pub mask: u32,
    /// Vertices in the grid.
    pub count: u32,
    /// r², the query's squared radius.
    pub radius2: f32,
    pub pad: u32,
}

impl GridParams {
    /// The constants for `count` vertices with bounding-box corner `min`, merged within
    /// `radius`.
    pub fn new(min: Vec3, count: u32, radius: f32) -> GridParams {
        GridParams {
            min: min.into(),
            inv_cell: 0.5 / radius,
            mask: count.max(1).next_power_of_two() - 1,
            count,
            radius2: radius * radius,
            pad: 0,
        }
    }

    pub fn buckets(&self) -> usize {
        self.mask as usize + 1
    }

    /// The point's position in cell units.
    #[inline]
    fn cell_units(&self, p: Vec3) -> Vec3 {
        ((p - Vec3::from(self.min)) * self.inv_cell)
            .clamp(Vec3::splat(-CELL_LIMIT), Vec3::splat(CELL_LIMIT))
    }

    /// The cell holding `p`.
    #[inline]
    pub fn cell(&self, p: Vec3) -> IVec3 {
        self.cell_units(p).floor().as_ivec3()
    }

    /// The bucket of the cell holding `p`.
    #[inline]
    pub fn bucket(&self, p: Vec3) -> u32 {
        hash_cell(self.cell(p)) & self.mask
    }

    /// The buckets of the cells that hold every point within `share` · r of `p` (share ≤ 1),
    /// each once: the first `n` entries of the array. A cell is 2r wide, so per axis the ball
    /// reaches at most the neighbour on the side of the nearer face, and that only where the
    /// face lies within share / 2 cell (with [`QUERY_MARGIN`]): 2x2x2 cells at share 1, and on
    /// average (1 + share)³ of them below, which is what a vertex merging within less than the
    /// grid's radius saves. Within the ball the same vertices are found in the same order.
    #[inline]
    pub fn query_buckets(&self, p: Vec3, share: f32) -> ([u32; 8], usize) {
        let u = self.cell_units(p);
        let c = u.floor();
        let f = u - c;
        let c = c.as_ivec3();
        // Per axis, the neighbour on the side of the nearer face, if the ball reaches it.
        let reach = 0.5 * share + QUERY_MARGIN;
        let side = |f: f32| {
            if f.min(1.0 - f) >= reach {
                0
            } else if f < 0.5 {
                -1
            } else {
                1
            }
        };
        let step = IVec3::new(side(f.x), side(f.y), side(f.z));
        let mut out = [0u32; 8];
        let mut n = 0;
        for k in 0..8 {
            let cell = c + IVec3::new(k & 1, (k >> 1) & 1, (k >> 2) & 1) * step;
            let b = hash_cell(cell) & self.mask;
            if !out[..n].contains(&b) {
                out[n] = b;
                n += 1;
            }
        }
        (out, n)
    }
}

/// The grid: constants, bucket starts (buckets + 1 entries) and the vertices by bucket, as
/// (position, index bits).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HashGrid {
    pub params: GridParams,
    pub starts: Vec<u32>,
    pub entries: Vec<[f32; 4]>,
}

/// The vertex index an entry holds.
#[inline]
pub fn entry_index(e: &[f32; 4]) -> u32 {
    e[3].to_bits()
}

impl Default for GridParams {
    fn default() -> Self {
        GridParams::new(Vec3::ZERO, 0, 1.0)
    }
}

impl HashGrid {
    /// Builds the grid of `items` (vertex i at `position(&items[i])`) for merging within
    /// `radius`, by counting sort, with cells counted from `min` (the scene's bounding-box
    /// corner, known to both backends before any vertex is traced). The buckets are hashed in
    /// parallel, once; counting and the scatter, which touch the arrays at hashed places, run
    /// in vertex order. `position` is called twice per vertex (to hash, then to scatter) and
    /// must give the same point both times.
    pub fn build<T: Sync>(
        items: &[T],
        position: impl Fn(&T) -> Vec3 + Sync,
        min: Vec3,
        radius: f32,
    ) -> HashGrid {
        let count = items.len() as u32;
        let params = GridParams::new(min, count, radius);
        let buckets: Vec<u32> = items
            .par_iter()
            .map(|x| params.bucket(position(x)))
            .collect();
        // Count per bucket, then the exclusive prefix sum: starts[b] is where bucket b begins.
        let mut starts = vec![0u32; params.buckets() + 1];
        for &b in &buckets {
            starts[b as usize + 1] += 1;
        }
        for b in 1..starts.len() {
            starts[b] += starts[b - 1];
        }
        // Scatter in vertex order, so each bucket lists its vertices in increasing index.
        let mut cursor = starts.clone();
        let mut entries = vec![[0.0f32; 4]; count as usize];
        for (i, (x, &b)) in items.iter().zip(&buckets).enumerate() {
            let p = position(x);
            entries[cursor[b as usize] as usize] = [p.x, p.y, p.z, f32::from_bits(i as u32)];
            cursor[b as usize] += 1;
        }
        HashGrid {
            params,
            starts,
            entries,
        }
    }

    /// Calls `visit(i)` for every vertex i whose position lies within r of `p`
    /// (|x − p|² < r²), bucket by bucket in the order of [`GridParams::query_buckets`].
    #[inline]
    pub fn query(&self, p: Vec3, visit: impl FnMut(u32)) {
        self.finish_query(&self.begin_query(p, 1.0), visit);
    }

    /// The first of a query's three steps ([`HashGrid::query`] runs them back to back): its
    /// buckets, whose ranges in `starts` it asks the memory system for without waiting.
    ///
    /// A query is bound by memory latency, not arithmetic: its buckets' ranges and entries lie
    /// at hashed places of arrays larger than the cache, and each step's addresses come from
    /// the loads of the one before. The camera pass knows a merge's point when it finds the
    /// hit, well before it merges, so it takes the steps apart with other work between them
    /// (next-event estimation, connections), and each step finds its data in the cache. A
    /// prefetch is a hint: what the query visits does not change.
    #[inline]
    pub fn begin_query(&self, p: Vec3, share: f32) -> PendingQuery {
        let (buckets, n) = if self.params.count == 0 {
            ([0; 8], 0)
        } else {
            self.params.query_buckets(p, share)
        };
        for &b in &buckets[..n] {
            prefetch(&self.starts[b as usize]);
        }
        PendingQuery { p, buckets, n }
    }

    /// The second step: the buckets' ranges (from the cache, if the first step was early
    /// enough), and a prefetch of their entries and of the same slots of `beside`, an array
    /// kept in entry order (the CPU's photon records).
    #[inline]
    pub fn prefetch_entries<T>(&self, query: &PendingQuery, beside: &[T]) {
        for &b in &query.buckets[..query.n] {
            let (start, end) = (self.starts[b as usize], self.starts[b as usize + 1]);
            if start < end {
                prefetch(&self.entries[start as usize]);
                prefetch(&self.entries[end as usize - 1]);
                if let (Some(first), Some(last)) =
                    (beside.get(start as usize), beside.get(end as usize - 1))
                {
                    prefetch(first);
                    prefetch(last);
                }
            }
        }
    }

    /// The last step: `visit(i)` for every vertex within r, as [`HashGrid::query`] says.
    #[inline]
    pub fn finish_query(&self, query: &PendingQuery, mut visit: impl FnMut(u32)) {
        self.finish_query_slots(query, |j| visit(entry_index(&self.entries[j])));
    }

    /// The last step, naming each vertex within r by its slot in `entries` (the same vertices
    /// in the same order as [`HashGrid::finish_query`]), for arrays kept in entry order.
    #[inline]
    pub fn finish_query_slots(&self, query: &PendingQuery, visit: impl FnMut(usize)) {
        self.finish_query_slots_within(query, self.params.radius2, visit)
    }

    /// [`HashGrid::finish_query_slots`] within a radius of its own (`radius2`, its square; VCM's
    /// vertices merge within their clearance, at most the grid's radius).
    #[inline]
    pub fn finish_query_slots_within(
        &self,
        query: &PendingQuery,
        radius2: f32,
        mut visit: impl FnMut(usize),
    ) {
        for &b in &query.buckets[..query.n] {
            let (start, end) = (self.starts[b as usize], self.starts[b as usize + 1]);
            within(
                &self.entries[start as usize..end as usize],
                query.p,
                radius2,
                |j| visit(start as usize + j),
            );
        }
    }
}

/// Calls `visit(j)` for every entry j of `entries` whose position lies within the radius of `p`
/// (|x − p|² < `radius2`), in order. Where the CPU has AVX, eight entries' distances are tested
/// at once: a query reads some 460 entries to find the few within r (tncg15_room at 256x256), and
/// one by one each test is a branch that the entry's place decides. The arithmetic is the
/// scalar test's, operation for operation, so the same entries are found.
#[inline]
fn within(entries: &[[f32; 4]], p: Vec3, radius2: f32, mut visit: impl FnMut(usize)) {
    let mut first = 0;
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX (checked above).
        first = unsafe { avx::within_by_eight(entries, p, radius2, &mut visit) };
    }
    for (j, e) in entries.iter().enumerate().skip(first) {
        if (Vec3::new(e[0], e[1], e[2]) - p).length_squared() < radius2 {
            visit(j);
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use glam::Vec3;
    use std::arch::x86_64::*;

    /// Bits 0..4 of the index spread to the even bits 0, 2, 4 and 6.
    const EVEN_BITS: [u32; 16] = [
        0b0000_0000,
        0b0000_0001,
        0b0000_0100,
        0b0000_0101,
        0b0001_0000,
        0b0001_0001,
        0b0001_0100,
        0b0001_0101,
        0b0100_0000,
        0b0100_0001,
        0b0100_0100,
        0b0100_0101,
        0b0101_0000,
        0b0101_0001,
        0b0101_0100,
        0b0101_0101,
    ];

    /// `super::within` for the whole groups of eight of `entries`; returns where the rest
    /// begins.
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[inline]
    #[target_feature(enable = "avx")]
    pub(super) fn within_by_eight(
        entries: &[[f32; 4]],
        p: Vec3,
        radius2: f32,
        visit: &mut impl FnMut(usize),
    ) -> usize {
        let (px, py, pz) = (
            _mm256_set1_ps(p.x),
            _mm256_set1_ps(p.y),
            _mm256_set1_ps(p.z),
        );
        let r2 = _mm256_set1_ps(radius2);
        let groups = entries.len() / 8;
        for g in 0..groups {
            let e = &entries[8 * g..8 * g + 8];
            // SAFETY: eight entries of four f32, two to a load.
            let row = |k: usize| unsafe { _mm256_loadu_ps(e[2 * k].as_ptr()) };
            let (r0, r1, r2_, r3) = (row(0), row(1), row(2), row(3));
            // Entries 0, 2, 4, 6 in the low lanes and 1, 3, 5, 7 in the high ones.
            let (t0, t1) = (_mm256_unpacklo_ps(r0, r1), _mm256_unpackhi_ps(r0, r1));
            let (t2, t3) = (_mm256_unpacklo_ps(r2_, r3), _mm256_unpackhi_ps(r2_, r3));
            let x = _mm256_shuffle_ps::<0b01_00_01_00>(t0, t2);
            let y = _mm256_shuffle_ps::<0b11_10_11_10>(t0, t2);
            let z = _mm256_shuffle_ps::<0b01_00_01_00>(t1, t3);
            // (x − p) · (x − p), added as `Vec3::length_squared` adds it.
            let (dx, dy, dz) = (
                _mm256_sub_ps(x, px),
                _mm256_sub_ps(y, py),
                _mm256_sub_ps(z, pz),
            );
            let d2 = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                _mm256_mul_ps(dz, dz),
            );
            let lanes = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(d2, r2)) as usize;
            // Back to entry order: lane k is entry 2k, lane 4 + k entry 2k + 1.
            let mut found = EVEN_BITS[lanes & 15] | EVEN_BITS[lanes >> 4] << 1;
            while found != 0 {
                visit(8 * g + found.trailing_zeros() as usize);
                found &= found - 1;
            }
        }
        8 * groups
    }
}

/// A query begun by [`HashGrid::begin_query`]: its point and buckets (the first `n`).
#[derive(Clone, Copy, Debug)]
pub struct PendingQuery {
    p: Vec3,
    buckets: [u32; 8],
    n: usize,
}

/// Asks for the cache line holding `x`, without waiting for it.
#[inline(always)]
fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch reads nothing into the program and cannot fault, whatever the address
    // (here that of a live reference); `_mm_prefetch` is SSE, which every x86-64 has.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>((x as *const T).cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What `within` finds, tested one entry at a time.
    fn within_one_by_one(entries: &[[f32; 4]], p: Vec3, radius2: f32) -> Vec<usize> {
        (0..entries.len())
            .filter(|&j| {
                let e = entries[j];
                (Vec3::new(e[0], e[1], e[2]) - p).length_squared() < radius2
            })
            .collect()
    }

    #[test]
    fn the_distance_test_eight_at_a_time_finds_the_same_entries_in_order() {
        let (p, r) = (Vec3::new(1.0, -2.0, 0.5), 0.5f32);
        // Entries about p out to twice r, a few exactly on the rim (|x − p|² = r², not within),
        // for every remainder of eight.
        let mut state = 12345u32;
        let mut next = || {
            state = state.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            (state >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
        };
        for n in [0, 1, 7, 8, 9, 16, 23, 64, 461] {
            let entries: Vec<[f32; 4]> = (0..n)
                .map(|j| {
                    let x = if j % 13 == 5 {
                        p + Vec3::new(0.0, r, 0.0)
                    } else {
                        p + Vec3::new(next(), next(), next()) * (2.0 * r)
                    };
                    [x.x, x.y, x.z, f32::from_bits(j as u32)]
                })
                .collect();
            let mut found = Vec::new();
            within(&entries, p, r * r, |j| found.push(j));
            assert_eq!(found, within_one_by_one(&entries, p, r * r), "{n} entries");
            if n >= 64 {
                assert!(!found.is_empty() && found.len() < n);
            }
        }
    }

    #[test]
    fn grid_params_have_the_shader_layout() {
        assert_eq!(std::mem::size_of::<GridParams>(), 32);
    }

    #[test]
    fn every_bucket_lists_its_vertices_in_increasing_order() {
        let points: Vec<Vec3> = (0..1000)
            .map(|i| {
                let f = i as f32;
                Vec3::new((f * 0.37).sin(), (f * 0.11).cos(), (f * 0.07).sin()) * 3.0
            })
            .collect();
        let grid = HashGrid::build(&points, |&p| p, Vec3::splat(-3.0), 0.05);
        assert_eq!(grid.entries.len(), 1000);
        for b in 0..grid.params.buckets() {
            let s: Vec<u32> = grid.entries[grid.starts[b] as usize..grid.starts[b + 1] as usize]
                .iter()
                .map(entry_index)
                .collect();
            assert!(s.windows(2).all(|w| w[0] < w[1]));
            assert!(s
                .iter()
                .all(|&i| grid.params.bucket(points[i as usize]) == b as u32));
        }
    }
}
