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

    #[inline]
    pub fn finish_query_slots_within(
        &self,
        query: &PendingQuery,
        radius2: f32,
        mut visit: impl FnMut(usize),
    ) {
        for &b in &query.buckets[..query.n] {
            let (start, end) = (self.starts[b as usize], self.starts[b as usize + 1]);
            for (j, e) in self.entries[start as usize..end as usize]
                .iter()
                .enumerate()
            {
                if (Vec3::new(e[0], e[1], e[2]) - query.p).length_squared() < radius2 {
                    visit(start as usize + j);
                }
            }
        }
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
