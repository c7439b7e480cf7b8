//! The CPU reference backend: the path integrator, run with rayon over image tiles.

pub mod path;

pub use path::{trace_path, Faults};

use crate::camera::Camera;
use crate::film::Film;
use crate::flat::FlatScene;
use crate::sampling::Sampler;
use rayon::prelude::*;

/// Tiles are square blocks of this many pixels on a side: big enough to amortise scheduling,
/// small enough that 2 to 64 threads balance on a 256x256 image.
pub const TILE: u32 = 16;

/// Adds samples `first..first + count` of every pixel to `film`, with rayon over tiles.
///
/// Each pixel's samples are added in sample order by one thread, whatever the thread count or
/// the split into passes, so an image is bit-identical for any `--threads` and pass schedule.
/// Returns the number of rays traced.
#[allow(clippy::too_many_arguments)]
pub fn render_pass(
    scene: &FlatScene,
    camera: &Camera,
    seed: u32,
    first: u32,
    count: u32,
    light_samples: u32,
    faults: Faults,
    film: &mut Film,
) -> u64 {
    let (w, h) = (film.width, film.height);
    let tiles_x = w.div_ceil(TILE);
    let tiles: Vec<(u32, u32)> = (0..h.div_ceil(TILE))
        .flat_map(|ty| (0..tiles_x).map(move |tx| (tx, ty)))
        .collect();
    let pixels = &film.pixels;
    let updated: Vec<(Vec<(usize, crate::film::PixelStats)>, u64)> = tiles
        .par_iter()
        .map(|&(tx, ty)| {
            let mut out = Vec::with_capacity((TILE * TILE) as usize);
            let mut rays = 0u64;
            for y in ty * TILE..((ty + 1) * TILE).min(h) {
                for x in tx * TILE..((tx + 1) * TILE).min(w) {
                    let index = (y * w + x) as usize;
                    let mut stats = pixels[index];
                    for s in first..first + count {
                        let sampler = Sampler::new(seed, index as u32, s);
                        stats.add(trace_path(
                            scene,
                            camera,
                            x,
                            y,
                            &sampler,
                            light_samples,
                            faults,
                            &mut rays,
                        ));
                    }
                    out.push((index, stats));
                }
            }
            (out, rays)
        })
        .collect();
    let mut rays = 0;
    for (tile, tile_rays) in updated {
        for (index, stats) in tile {
            film.pixels[index] = stats;
        }
        rays += tile_rays;
    }
    rays
}
