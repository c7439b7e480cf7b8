//! The CPU reference backend: the integrators, run with rayon over image tiles (path tracing)
//! or over iterations of a light pass and a camera pass (light tracing, BDPT, SPPM, VCM).

pub mod bdpt;
pub mod dark_image;
pub mod light_path;
pub mod path;
pub mod path_wavefront;
pub mod photon_map;
pub mod radiosity;
pub mod shadow_probe;
pub mod whitted;

use crate::transport::faults::Faults;
pub use path::trace_path;

use crate::accel::hash_grid::{entry_index, HashGrid};
use crate::film::{Film, PixelRun, PixelStats};
use crate::layout::FlatScene;
use crate::math::sampling::{Sampler, SamplerKind};
use crate::transport::camera::Camera;
use crate::transport::merging::{kernel_normalization, MergeRadius};
use crate::transport::method::Method;
use crate::transport::splat::Splats;
use crate::transport::subpath::{LightVertex, MergeMis, PhotonRecord};
use light_path::{LightPass, LightPassMode};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// Tiles are square blocks of this many pixels on a side: big enough to amortise scheduling,
/// small enough that 2 to 64 threads balance on a 256x256 image.
pub const TILE: u32 = 16;

/// A stop that is never asked for, for the renders that run to their end.
static NEVER: AtomicBool = AtomicBool::new(false);

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
    render_pass_until(
        scene,
        camera,
        seed,
        first,
        count,
        light_samples,
        faults,
        film,
        &NEVER,
    )
}

/// [`render_pass`] until `stop` is set: a pass stopped before its end leaves `film` as it was
/// (its tiles not yet begun are skipped), so that a stop takes effect within a tile's time.
#[allow(clippy::too_many_arguments)]
pub fn render_pass_until(
    scene: &FlatScene,
    camera: &Camera,
    seed: u32,
    first: u32,
    count: u32,
    light_samples: u32,
    faults: Faults,
    film: &mut Film,
    stop: &AtomicBool,
) -> u64 {
    // The tile's pixels, their paths traced together (`path_wavefront::trace_pixels`).
    let kind = film.sampler;
    render_tiles_until(film, stop, |tile, stats, rays| {
        path_wavefront::trace_pixels(
            scene,
            camera,
            tile,
            kind,
            seed,
            first,
            count,
            light_samples,
            faults,
            stats,
            rays,
        )
    })
}

/// Adds adaptive sampling's runs of path tracing to `film` (`crate::render::adaptive`): the
/// runs of each tile's pixels traced together (`path_wavefront::trace_pixel_samples`), each
/// added to its pixel with the run's weight. `stop` drops the pass whole, as
/// [`render_pass_until`]'s. Returns the number of rays traced.
#[allow(clippy::too_many_arguments)]
pub fn render_path_runs_until(
    scene: &FlatScene,
    camera: &Camera,
    seed: u32,
    runs: &[PixelRun],
    light_samples: u32,
    faults: Faults,
    film: &mut Film,
    stop: &AtomicBool,
) -> u64 {
    let (kind, w) = (film.sampler, film.width);
    let tile_of = |r: &PixelRun| {
        let (x, y) = (r.pixel % w, r.pixel / w);
        (y / TILE) * w.div_ceil(TILE) + x / TILE
    };
    let mut order: Vec<&PixelRun> = runs.iter().collect();
    order.sort_by_key(|r| (tile_of(r), r.pixel));
    let tiles: Vec<&[&PixelRun]> = order.chunk_by(|a, b| tile_of(a) == tile_of(b)).collect();
    let traced: Vec<(Vec<PixelStats>, u64)> = tiles
        .par_iter()
        .map(|tile| {
            if stop.load(Ordering::Relaxed) {
                return (Vec::new(), 0);
            }
            let pixels: Vec<(u32, u32, u32)> = tile
                .iter()
                .map(|r| (r.pixel, r.pixel % w, r.pixel / w))
                .collect();
            let mut stats = vec![PixelStats::default(); tile.len()];
            let mut rays = 0;
            path_wavefront::trace_pixel_samples(
                scene,
                camera,
                &pixels,
                |p| tile[p].first..tile[p].first + tile[p].count,
                kind,
                seed,
                light_samples,
                faults,
                &mut stats,
                &mut rays,
            );
            (stats, rays)
        })
        .collect();
    let rays = traced.iter().map(|(_, r)| r).sum();
    if stop.load(Ordering::SeqCst) {
        return rays;
    }
    for (tile, (stats, _)) in tiles.iter().zip(&traced) {
        for (run, batch) in tile.iter().zip(stats) {
            let weight = if faults.adaptive_pooled {
                1.0
            } else {
                run.weight
            };
            film.pixels[run.pixel as usize].merge_weighted(batch, weight);
        }
    }
    rays
}

/// Adds samples `first..first + count` of Whitted ray tracing (`whitted::trace_whitted`) to
/// every pixel of `film`, with rayon over tiles, as [`render_pass`] does path tracing's.
/// Returns the number of rays traced.
pub fn render_whitted_pass(
    scene: &FlatScene,
    camera: &Camera,
    seed: u32,
    first: u32,
    count: u32,
    faults: Faults,
    film: &mut Film,
) -> u64 {
    render_whitted_pass_until(scene, camera, seed, first, count, faults, film, &NEVER)
}

/// [`render_whitted_pass`] until `stop` is set, as [`render_pass_until`].
#[allow(clippy::too_many_arguments)]
pub fn render_whitted_pass_until(
    scene: &FlatScene,
    camera: &Camera,
    seed: u32,
    first: u32,
    count: u32,
    faults: Faults,
    film: &mut Film,
    stop: &AtomicBool,
) -> u64 {
    render_samples_until(film, stop, seed, first, count, |x, y, sampler, rays| {
        whitted::trace_whitted(scene, camera, x, y, sampler, faults, rays)
    })
}

/// Adds samples `first..first + count` of radiosity's image (`radiosity::trace_radiosity`,
/// over the solved `solution`) to every pixel of `film`, as [`render_whitted_pass`] does
/// Whitted's. Returns the number of rays traced.
#[allow(clippy::too_many_arguments)]
pub fn render_radiosity_pass(
    scene: &FlatScene,
    camera: &Camera,
    solution: &radiosity::Solution,
    seed: u32,
    first: u32,
    count: u32,
    faults: Faults,
    film: &mut Film,
) -> u64 {
    render_radiosity_pass_until(
        scene, camera, solution, seed, first, count, faults, film, &NEVER,
    )
}

/// [`render_radiosity_pass`] until `stop` is set, as [`render_pass_until`].
#[allow(clippy::too_many_arguments)]
pub fn render_radiosity_pass_until(
    scene: &FlatScene,
    camera: &Camera,
    solution: &radiosity::Solution,
    seed: u32,
    first: u32,
    count: u32,
    faults: Faults,
    film: &mut Film,
    stop: &AtomicBool,
) -> u64 {
    render_samples_until(film, stop, seed, first, count, |x, y, sampler, rays| {
        radiosity::trace_radiosity(scene, camera, solution, x, y, sampler, faults, rays)
    })
}

/// Samples `first..first + count` of every pixel, each the radiance `trace(x, y, sampler,
/// rays)` of one camera sample drawing the pixel's stream, added to `film` tile by tile until
/// `stop` is set (Whitted's and radiosity's images).
fn render_samples_until(
    film: &mut Film,
    stop: &AtomicBool,
    seed: u32,
    first: u32,
    count: u32,
    trace: impl Fn(u32, u32, &Sampler, &mut u64) -> glam::Vec3 + Sync,
) -> u64 {
    let kind = film.sampler;
    render_tiles_until(film, stop, |tile, stats, rays| {
        for (&(index, x, y), stats) in tile.iter().zip(stats) {
            for s in first..first + count {
                stats.add(trace(x, y, &Sampler::of(kind, seed, index, s), rays));
            }
        }
    })
}

/// Runs `trace_tile` over the image's tiles in parallel, each with its pixels (index, x, y),
/// their statistics so far to add samples to, and a ray counter; puts the tiles' statistics
/// into `film`, unless `stop` was set, which skips the tiles not yet begun and leaves `film` as
/// it was. Returns the number of rays traced.
fn render_tiles_until(
    film: &mut Film,
    stop: &AtomicBool,
    trace_tile: impl Fn(&[(u32, u32, u32)], &mut [PixelStats], &mut u64) + Sync,
) -> u64 {
    let (w, h) = (film.width, film.height);
    let tiles_x = w.div_ceil(TILE);
    let tiles: Vec<(u32, u32)> = (0..h.div_ceil(TILE))
        .flat_map(|ty| (0..tiles_x).map(move |tx| (tx, ty)))
        .collect();
    let pixels = &film.pixels;
    let updated: Vec<(Vec<(usize, PixelStats)>, u64)> = tiles
        .par_iter()
        .map(|&(tx, ty)| {
            if stop.load(Ordering::Relaxed) {
                return (Vec::new(), 0);
            }
            let mut tile = Vec::with_capacity((TILE * TILE) as usize);
            for y in ty * TILE..((ty + 1) * TILE).min(h) {
                for x in tx * TILE..((tx + 1) * TILE).min(w) {
                    tile.push((y * w + x, x, y));
                }
            }
            let mut stats: Vec<PixelStats> =
                tile.iter().map(|&(i, _, _)| pixels[i as usize]).collect();
            let mut rays = 0u64;
            trace_tile(&tile, &mut stats, &mut rays);
            let out: Vec<(usize, PixelStats)> = tile
                .iter()
                .zip(stats)
                .map(|(&(i, _, _), s)| (i as usize, s))
                .collect();
            (out, rays)
        })
        .collect();
    let mut rays = 0;
    if stop.load(Ordering::SeqCst) {
        // Stopped: the pass's samples are dropped whole, so every pixel keeps as many.
        return updated.iter().map(|(_, r)| r).sum();
    }
    for (tile, tile_rays) in updated {
        for (index, stats) in tile {
            film.pixels[index] = stats;
        }
        rays += tile_rays;
    }
    rays
}

/// One tile's pixel values of an iteration (None where a splat sum overflowed), and its rays.
type TileValues = (Vec<(usize, Option<glam::Vec3>)>, u64);

/// Light subpaths per parallel task of the light pass.
const LIGHT_CHUNK: u32 = 256;

/// What the iterations of the light-subpath methods share: the splats and (but for light
/// tracing) the light subpaths' stored vertices of the current iteration, subpath i's at
/// `vertices[starts[i]..starts[i + 1]]`, kept so that nothing is allocated per iteration but
/// the chunks' lists, and their hash grid (merging); and what is fixed for the scene and
/// camera, n_c per pixel, τ and the merge radius's schedule.
pub struct LightPassBuffers {
    pub splats: Splats,
    pub vertices: Vec<LightVertex>,
    pub starts: Vec<u32>,
    pub grid: HashGrid,
    /// The photons' records in the grid's entry order (merging; `PhotonRecord`).
    pub records: Vec<PhotonRecord>,
    /// The grid's origin: the scene's bounding-box corner (`merging::scene_bounds`).
    pub grid_min: glam::Vec3,
    /// The merge radius's schedule (SPPM, VCM).
    pub radius: MergeRadius,
    /// n_c per pixel (`subpath::camera_subpaths`).
    pub camera_subpaths: Vec<u32>,
    /// τ (`shadow_probe::shadow_threshold`; BDPT only, 0 for light tracing).
    pub shadow_threshold: f32,
}

impl LightPassBuffers {
    pub fn new(
        scene: &FlatScene,
        camera: &Camera,
        method: Method,
        radius: MergeRadius,
    ) -> LightPassBuffers {
        let bdpt = method != Method::Light;
        LightPassBuffers {
            splats: Splats::new(camera.width, camera.height),
            vertices: Vec::new(),
            starts: Vec::new(),
            grid: HashGrid::default(),
            records: Vec::new(),
            grid_min: crate::transport::merging::scene_bounds(scene).0,
            radius,
            camera_subpaths: if bdpt {
                crate::transport::subpath::camera_subpaths(
                    &crate::transport::subpath::specular_pixels(scene, camera),
                    crate::transport::subpath::specular_camera_subpaths(method, radius.initial),
                )
            } else {
                vec![1; camera.width as usize * camera.height as usize]
            },
            shadow_threshold: shadow_probe::shadow_threshold_for(method, scene, camera),
        }
    }
}

/// Adds iterations `first..first + count` of light tracing, BDPT, SPPM or VCM to `film`. Each
/// iteration traces N light subpaths (light pass, splatting into `buffers.splats`; N is one per
/// pixel up to a bound, `merging::light_paths`), builds the hash grid of
/// their vertices (merging, with iteration i's radius), then n_c camera subpaths per pixel
/// (`subpath::camera_subpaths`; not for light tracing) that connect to light subpath
/// (pixel index mod N) and merge with every light subpath's vertices; each pixel's value for
/// the iteration, the mean of its camera subpaths' radiance plus the splats it received, is one
/// sample of that pixel, and the iteration's image mean one sample of the image mean (batch
/// means, `crate::film::Film`). Splat sums do not depend on thread order, so images are bit-identical for
/// any thread count. Returns the number of rays traced.
#[allow(clippy::too_many_arguments)]
pub fn render_iterations(
    scene: &FlatScene,
    camera: &Camera,
    seed: u32,
    first: u32,
    count: u32,
    method: Method,
    faults: Faults,
    buffers: &mut LightPassBuffers,
    film: &mut Film,
) -> u64 {
    render_iterations_until(
        scene, camera, seed, first, count, method, faults, buffers, film, &NEVER,
    )
}

/// [`render_iterations`] until `stop` is set: the iteration under way when it is set is dropped
/// (its chunks and tiles not yet begun are skipped, its splats cleared), and the iterations
/// before it stay in `film`. So a stop takes effect within a tile's time, whatever the image
/// size, and each pixel keeps whole iterations only, which is what keeps the image unbiased.
#[allow(clippy::too_many_arguments)]
pub fn render_iterations_until(
    scene: &FlatScene,
    camera: &Camera,
    seed: u32,
    first: u32,
    count: u32,
    method: Method,
    faults: Faults,
    buffers: &mut LightPassBuffers,
    film: &mut Film,
    stop: &AtomicBool,
) -> u64 {
    assert!(method.splats(), "{method} does not trace light subpaths");
    let pixels = film.width * film.height;
    let n_paths = buffers.radius.light_paths_for(method, pixels as u64);
    // N as the estimators count it (the pixels under the planted fault).
    let n_counted = if faults.light_paths_counted_per_pixel {
        pixels
    } else {
        n_paths
    };
    let mode = match method {
        Method::Light => LightPassMode::LightTracing,
        Method::Sppm => LightPassMode::PhotonMapping,
        Method::PhotonMap => LightPassMode::CausticAndGlobal,
        _ => LightPassMode::Bidirectional,
    };
    let mut rays = 0u64;
    for s in first..first + count {
        if stop.load(Ordering::SeqCst) {
            break;
        }
        // Merging's radius this iteration, and its constants in the MIS weights.
        let radius = if method.merges() {
            buffers.radius.at(s)
        } else {
            0.0
        };
        let iteration = Iteration {
            scene,
            camera,
            sampler: film.sampler,
            seed,
            s,
            method,
            faults,
            n_paths,
            n_counted,
            radius,
            reach: buffers.radius.reach,
            merge: MergeMis::new(radius, n_counted, method),
            stop,
        };
        rays += iteration.light_pass(mode, buffers);
        if !stop.load(Ordering::SeqCst) && radius > 0.0 {
            iteration.build_grid(buffers);
        }
        let results = iteration.camera_pass(buffers, film.width, film.height);
        if stop.load(Ordering::SeqCst) {
            // Stopped under way: the iteration is dropped, its splats with it.
            buffers.splats.clear();
            rays += results.iter().map(|(_, r)| r).sum::<u64>();
            break;
        }
        rays += add_iteration(film, results);
    }
    rays
}

/// One iteration of the light-subpath methods: what its light pass and camera pass share.
struct Iteration<'a> {
    scene: &'a FlatScene,
    camera: &'a Camera,
    /// The streams: every pixel's (and light subpath's) samples under `seed`, drawn by `sampler`.
    sampler: SamplerKind,
    seed: u32,
    /// The iteration's index: its sample index in every pixel's streams.
    s: u32,
    method: Method,
    faults: Faults,
    /// N, the light subpaths of an iteration: one per pixel up to a bound
    /// (`merging::light_paths`).
    n_paths: u32,
    /// N as the kernel, the splats and the MIS weights count it: `n_paths` (but for the planted
    /// fault `Faults::light_paths_counted_per_pixel`).
    n_counted: u32,
    /// The largest merge radius of this iteration (0: no merging).
    radius: f32,
    /// The view's reach (`MergeRadius::reach`).
    reach: f32,
    merge: MergeMis,
    /// A stop asked for: the chunks and tiles not yet begun are skipped.
    stop: &'a AtomicBool,
}

impl Iteration<'_> {
    /// Whether the camera vertices merge within their clearance rather than the full radius.
    fn local_radius(&self) -> bool {
        self.method.merges_within_clearance()
            && self.radius > 0.0
            && !self.faults.merge_ignores_clearance
    }

    /// The light pass: every light subpath, in chunks; the chunks' vertices are joined in
    /// subpath order into `buffers`, their splats added to `buffers.splats`. Returns the rays.
    fn light_pass(&self, mode: LightPassMode, buffers: &mut LightPassBuffers) -> u64 {
        let (scene, seed, s, n_paths) = (self.scene, self.seed, self.s, self.n_paths);
        let kind = self.sampler;
        let pass = LightPass {
            scene,
            camera: self.camera,
            n_light_paths: self.n_counted,
            mode,
            faults: self.faults,
            camera_subpaths: &buffers.camera_subpaths,
            shadow_threshold: buffers.shadow_threshold,
            merge: self.merge,
            merges: self.radius > 0.0,
            radius: self.radius,
            reach: self.reach,
            local_radius: self.local_radius(),
        };
        let chunks: Vec<(Vec<LightVertex>, Vec<u32>, u64)> = (0..n_paths.div_ceil(LIGHT_CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut vertices = Vec::new();
                let mut ends = Vec::with_capacity(LIGHT_CHUNK as usize);
                if self.stop.load(Ordering::Relaxed) {
                    return (vertices, ends, 0);
                }
                let mut rays = 0;
                let mut pending = Vec::new();
                for i in c * LIGHT_CHUNK..((c + 1) * LIGHT_CHUNK).min(n_paths) {
                    rays += pass.trace_light_path(
                        i,
                        &Sampler::of(kind, seed, i, s),
                        &mut pending,
                        &mut vertices,
                    );
                    ends.push(vertices.len() as u32);
                }
                // The chunk's splats, their visibility rays in packets.
                light_path::add_splats(scene, &pending, &buffers.splats);
                (vertices, ends, rays)
            })
            .collect();
        let mut rays = 0;
        buffers.vertices.clear();
        buffers.starts.clear();
        buffers.starts.push(0);
        for (vertices, ends, chunk_rays) in chunks {
            let base = buffers.vertices.len() as u32;
            buffers.starts.extend(ends.iter().map(|e| base + e));
            buffers.vertices.extend_from_slice(&vertices);
            rays += chunk_rays;
        }
        rays
    }

    /// The hash grid of the iteration's light vertices, and what a merge reads of each in the
    /// grid's entry order.
    fn build_grid(&self, buffers: &mut LightPassBuffers) {
        let merge = &self.merge;
        buffers.grid = HashGrid::build(
            &buffers.vertices,
            |v| v.p.into(),
            buffers.grid_min,
            self.radius,
        );
        let (vertices, connects) = (&buffers.vertices, self.method.connects());
        buffers.records.clear();
        buffers.records.par_extend(
            buffers
                .grid
                .entries
                .par_iter()
                .map(|e| PhotonRecord::new(&vertices[entry_index(e) as usize], merge, connects)),
        );
    }

    /// The camera pass: each pixel's camera subpaths, tile by tile, plus its splats; each
    /// pixel's value for the iteration (None where its splat sum overflowed), with the rays.
    fn camera_pass(&self, buffers: &LightPassBuffers, w: u32, h: u32) -> Vec<TileValues> {
        let (scene, seed, s, n_paths) = (self.scene, self.seed, self.s, self.n_paths);
        let kind = self.sampler;
        let (method, faults, radius, merge) = (self.method, self.faults, self.radius, self.merge);
        let camera_pass = bdpt::CameraPass {
            scene,
            camera: self.camera,
            n_light_paths: self.n_counted,
            faults,
            shadow_threshold: buffers.shadow_threshold,
            connects: method.connects(),
            merge,
            radius,
            reach: self.reach,
            local_radius: self.local_radius(),
            photons: (radius > 0.0).then(|| {
                debug_assert_eq!(buffers.records.len(), buffers.grid.entries.len());
                bdpt::Photons {
                    records: &buffers.records,
                    grid: &buffers.grid,
                    normalization: kernel_normalization(
                        radius,
                        self.n_counted,
                        faults.merge_kernel_ball,
                    ),
                }
            }),
        };
        let photon_map = camera_pass
            .photons
            .filter(|_| method == Method::PhotonMap)
            .map(|photons| photon_map::PhotonMapPass {
                scene,
                camera: self.camera,
                faults,
                photons,
                radius,
            });
        let tiles_x = w.div_ceil(TILE);
        (0..tiles_x * h.div_ceil(TILE))
            .into_par_iter()
            .map_init(bdpt::CameraTerms::default, |terms, t| {
                if self.stop.load(Ordering::Relaxed) {
                    return (Vec::new(), 0);
                }
                let (tx, ty) = (t % tiles_x, t / tiles_x);
                let mut rays = 0;
                // The tile's camera subpaths, their visibility rays traced together (at the end,
                // or sooner where they pile up) and each subpath's radiance in order.
                let mut pixels = Vec::with_capacity((TILE * TILE) as usize);
                let mut radiance = Vec::new();
                for y in ty * TILE..((ty + 1) * TILE).min(h) {
                    for x in tx * TILE..((tx + 1) * TILE).min(w) {
                        let index = (y * w + x) as usize;
                        let n_c = if let Some(pass) = &photon_map {
                            // Photon mapping: the pixel's n_c camera samples, each gathering
                            // from the iteration's photon maps (no light subpath of its own).
                            let n_c = buffers.camera_subpaths[index];
                            for k in 0..n_c {
                                let sampler = Sampler::of(kind, seed, index as u32 + k * w * h, s);
                                radiance.push(pass.trace_camera_path(x, y, &sampler, &mut rays));
                            }
                            n_c
                        } else if method != Method::Light {
                            // The pixel's n_c camera subpaths, averaged, each connecting to
                            // light subpath index mod N; the k-th draws the streams of pixel
                            // index + k · w · h (a camera subpath's own blocks there: light
                            // subpaths stop at N ≤ w · h).
                            let path = index % n_paths as usize;
                            let (a, b) = (buffers.starts[path], buffers.starts[path + 1]);
                            let light_path = &buffers.vertices[a as usize..b as usize];
                            let n_c = buffers.camera_subpaths[index];
                            for k in 0..n_c {
                                let sampler = Sampler::of(kind, seed, index as u32 + k * w * h, s);
                                camera_pass.trace_camera_path(
                                    x, y, n_c, &sampler, light_path, terms, &mut rays,
                                );
                            }
                            n_c
                        } else {
                            0
                        };
                        pixels.push((index, n_c));
                        if terms.pending_rays() >= bdpt::CameraTerms::RAYS_BEFORE_SUM {
                            terms.sum_into(scene, &mut radiance);
                        }
                    }
                }
                terms.sum_into(scene, &mut radiance);
                // Each pixel's subpaths averaged, plus its splats.
                let mut radiance = radiance.into_iter();
                let out = pixels
                    .into_iter()
                    .map(|(index, n_c)| {
                        let mut value = glam::Vec3::ZERO;
                        if n_c > 0 {
                            for r in radiance.by_ref().take(n_c as usize) {
                                value += r;
                            }
                            value /= n_c as f32;
                        }
                        (index, buffers.splats.take(index).map(|splat| value + splat))
                    })
                    .collect();
                debug_assert!(radiance.next().is_none(), "a subpath's radiance left over");
                (out, rays)
            })
            .collect()
    }
}

/// Adds an iteration's pixel values to the film, one sample per pixel, and the iteration's image
/// mean as one sample of the image's (batch means). Returns the camera pass's rays.
fn add_iteration(film: &mut Film, results: Vec<TileValues>) -> u64 {
    let (w, h) = (film.width, film.height);
    let mut rays = 0;
    // One sample per pixel, and the iteration's image mean as one sample of the image's.
    let mut image_sum = glam::DVec3::ZERO;
    for (tile, tile_rays) in results {
        for (index, value) in tile {
            // A splat sum that overflowed is dropped like a non-finite sample.
            let v = value.unwrap_or(glam::Vec3::NAN);
            film.pixels[index].add(v);
            if v.is_finite() {
                image_sum += v.as_dvec3();
            }
        }
        rays += tile_rays;
    }
    film.iteration_means
        .get_or_insert_with(PixelStats::default)
        .add((image_sum / (w as f64 * h as f64)).as_vec3());
    rays
}
