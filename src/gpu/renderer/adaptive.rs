//! Adaptive sampling's passes on the GPU (`crate::render::adaptive`): each pixel its own run of
//! samples, from a buffer of runs that the dispatch covers instead of a tile of pixels
//! (`render_pass` in `shaders/path.wgsl` with `frame.run_count` set).

use super::GpuRenderer;
use crate::film::{Film, PixelRun};
use crate::gpu::frame::{Frame, MAX_PASS_SPP, WORKGROUP};
use crate::transport::method::Method;
use anyhow::{ensure, Result};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Runs per row of the grid a dispatch lays them out in: one workgroup wide, so that each
/// workgroup takes WORKGROUP² consecutive runs (of about as many samples, in the sorted order).
const RUNS_PER_ROW: u32 = WORKGROUP;

/// The most runs one dispatch covers: a grid one workgroup wide and the most workgroups a
/// dimension may have (wgpu's default `max_compute_workgroups_per_dimension`).
const MAX_RUNS_PER_DISPATCH: usize = 65535 * (WORKGROUP * WORKGROUP) as usize;

impl GpuRenderer {
    /// Adds each run's samples to its pixel, folded into the film with the run's weight
    /// (`PixelStats::merge_weighted`; 1 under the planted fault `Faults::adaptive_pooled`).
    /// The pass sums are f32, so a run longer than MAX_PASS_SPP is spread over sub-passes of
    /// that many samples each; `stop` drops the sub-pass under way (those before it stay).
    pub fn adaptive_pass_until(
        &mut self,
        runs: &[PixelRun],
        film: &mut Film,
        stop: &AtomicBool,
    ) -> Result<()> {
        ensure!(
            self.method == Method::Path,
            "adaptive sampling is available for path tracing only, not {}",
            self.method
        );
        crate::film::check_film_for(self.method, film)?;
        self.frame.sampler = film.sampler.code();
        let mut weights = vec![0.0; film.pixels.len()];
        for r in runs {
            weights[r.pixel as usize] = if self.faults.adaptive_pooled {
                1.0
            } else {
                r.weight
            };
        }
        let mut taken = 0;
        loop {
            // Each run's next MAX_PASS_SPP samples at most: [pixel, first, count, 0].
            let sub: Vec<[u32; 4]> = runs
                .iter()
                .filter(|r| r.count > taken)
                .map(|r| {
                    [
                        r.pixel,
                        r.first + taken,
                        (r.count - taken).min(MAX_PASS_SPP),
                        0,
                    ]
                })
                .collect();
            if sub.is_empty() || !self.runs_pass(&sub, film, &weights, stop)? {
                return Ok(());
            }
            taken += MAX_PASS_SPP;
        }
    }

    /// One sub-pass of runs: per film band, the band's runs uploaded longest first (so that a
    /// workgroup's lanes have about as many samples each), dispatched in slices of about
    /// `paths_per_dispatch` paths; false if `stop` cut it short (nothing folded).
    fn runs_pass(
        &mut self,
        runs: &[[u32; 4]],
        film: &mut Film,
        weights: &[f64],
        stop: &AtomicBool,
    ) -> Result<bool> {
        self.check_device()?;
        let width = self.frame.camera.width;
        let paths: u64 = runs.iter().map(|r| r[2] as u64).sum();
        let checked = self.stop_checked(paths, 1);
        let start = Instant::now();
        let finished = self.for_each_weighted_film_band(
            film,
            self.film_rows,
            |p| weights[p],
            |a, z| {
                let mut band: Vec<[u32; 4]> = runs
                    .iter()
                    .filter(|r| (a..z).contains(&(r[0] / width)))
                    .copied()
                    .collect();
                if band.is_empty() {
                    return true;
                }
                band.sort_by_key(|r| std::cmp::Reverse(r[2]));
                self.queue
                    .write_buffer(&self.runs, 0, bytemuck::cast_slice(&band));
                self.dispatch_runs(&band, a, z, stop, checked && a == 0)
            },
        )?;
        if finished {
            let paths_per_second = paths as f64 / start.elapsed().as_secs_f64();
            self.paths_per_dispatch =
                ((paths_per_second * crate::gpu::frame::TARGET_DISPATCH_SECONDS) as u64)
                    .clamp(4096, 1 << 28);
        }
        Ok(finished)
    }

    /// Queues the band's runs (rows `band_start..band_end`, uploaded in this order) in
    /// dispatches of about `paths_per_dispatch` paths, each over a grid of RUNS_PER_ROW runs a
    /// row. With `checked`, each dispatch is waited for and `stop` looked at before the next;
    /// returns false if it was set.
    fn dispatch_runs(
        &self,
        band: &[[u32; 4]],
        band_start: u32,
        band_end: u32,
        stop: &AtomicBool,
        checked: bool,
    ) -> bool {
        let mut offset = 0;
        while offset < band.len() {
            let (mut k, mut paths) = (0, 0u64);
            while offset + k < band.len()
                && k < MAX_RUNS_PER_DISPATCH
                && (k == 0 || paths < self.paths_per_dispatch)
            {
                paths += band[offset + k][2] as u64;
                k += 1;
            }
            let frame = Frame {
                first_sample: 0,
                sample_count: 1,
                tile_origin: [0, 0],
                tile_size: [RUNS_PER_ROW, (k as u32).div_ceil(RUNS_PER_ROW)],
                run_offset: offset as u32,
                run_count: k as u32,
                film_row: band_start,
                film_rows: band_end - band_start,
                ..self.frame
            };
            self.dispatch_pass(&frame);
            offset += k;
            if offset < band.len() && self.stop_seen(stop, checked) {
                return false;
            }
        }
        true
    }
}
