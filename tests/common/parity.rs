//! The parity statistic of `tests/gpu_parity.rs` for any two films.

use super::{Backend, Render};
use glam::Vec3;
use hexray::analysis::stats::{welch_blocks, MeanImage};
use hexray::film::Film;
use hexray::transport::faults::Faults;
use hexray::transport::method::Method;

/// Two images compared per 8x8 block and channel (Welch's t, Bonferroni α = 0.01 over all
/// block-channels) and by their image-mean ratio b / a per channel with its standard error.
#[derive(Clone, Debug)]
pub struct Parity {
    pub rejected: usize,
    pub tests: usize,
    pub smallest_p: f64,
    pub largest_t: f64,
    pub ratio: [f64; 3],
    pub ratio_se: [f64; 3],
    pub ratio_z: [f64; 3],
}

impl Parity {
    /// No block-channel rejected and every channel's mean ratio within 4 s.e. of 1.
    pub fn same(&self) -> bool {
        self.rejected == 0 && self.ratio_z.iter().all(|z| z.abs() <= 4.0)
    }
}

impl std::fmt::Display for Parity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} of {} block-channels rejected (smallest p {:.2e}, largest |t| {:.2}); mean ratio \
             {:.4} {:.4} {:.4} (s.e. {:.4} {:.4} {:.4}), z {:.2} {:.2} {:.2}",
            self.rejected,
            self.tests,
            self.smallest_p,
            self.largest_t,
            self.ratio[0],
            self.ratio[1],
            self.ratio[2],
            self.ratio_se[0],
            self.ratio_se[1],
            self.ratio_se[2],
            self.ratio_z[0],
            self.ratio_z[1],
            self.ratio_z[2]
        )
    }
}

/// `tests/gpu_parity.rs`'s statistic: the two films must be independent renders (other seeds).
pub fn parity(a: &Film, b: &Film) -> Parity {
    let (a, b) = (MeanImage::from_film(a), MeanImage::from_film(b));
    compare(&a.blocks(8), &b.blocks(8), a.grand_mean(), b.grand_mean())
}

/// [`parity`] for two independent renders given as their iterations' films (one film per
/// iteration), for the methods whose pixels share an iteration's photons and splats. An
/// iteration is one independent estimate of every block and of the image, so each block's
/// standard error comes from the scatter of its per-iteration means (batch means). That counts
/// the covariance of the pixels that merged the same photons, which [`parity`]'s sum of pixel
/// variances leaves out: measured over 24 seeds of sppm on tncg15_room at 64x64, 48 iterations,
/// the block means scatter 0.94x the variance that sum claims at `--radius` 0.003 of the scene
/// radius and 1.10x at 0.01, where the disk is about a pixel wide on the walls. The iterations are
/// independent but not identically distributed (the radius shrinks, and the bias with it); their
/// scatter then also holds the drift of their expectations, the same on both sides, which makes
/// the standard error a little conservative, not too small.
pub fn parity_of_iterations(a: &[Film], b: &[Film]) -> Parity {
    let (a, b) = (batch_blocks(a, 8), batch_blocks(b, 8));
    compare(&a, &b, a.grand_mean(), b.grand_mean())
}

/// [`parity_of_iterations`] between a CPU render (seed 80) and a GPU render (seed 81, with
/// `gpu_faults`) of `iterations` iterations of `method` at `size` x `size`, each iteration
/// rendered alone; None without a GPU. The GPU = CPU tests of every method that splats or
/// merges (light, bdpt, sppm, vcm) use it.
pub fn gpu_against_cpu_iterations(
    rel: &str,
    size: u32,
    iterations: u32,
    method: Method,
    radius: hexray::transport::merging::MergeRadius,
    gpu_faults: Faults,
) -> Option<Parity> {
    super::gpu()?;
    let n = iterations;
    let render = Render::file(rel)
        .size(size, size)
        .spp(n)
        .method(method)
        .radius(radius);
    let a = render.seed(80).iterations_on(Backend::Cpu);
    let b = render
        .seed(81)
        .faults(gpu_faults)
        .iterations_on(Backend::Gpu);
    let p = parity_of_iterations(&a, &b);
    eprintln!("{method} {rel}, {n} iterations, GPU against CPU, batch means: {p}");
    Some(p)
}

/// The `b` x `b` block means of each iteration's film, each block's taken as one sample of a
/// film whose pixels are the blocks, and each iteration's image mean as one of its
/// `iteration_means`: that film's pixel means and variances of the mean are the batch means
/// and their variances, and its image mean's standard error theirs.
fn batch_blocks(films: &[Film], b: usize) -> MeanImage {
    let mut batches: Option<Film> = None;
    for film in films {
        let blocks = MeanImage::from_film(film).blocks(b);
        let batches = batches.get_or_insert_with(|| {
            Film::with_iteration_means(blocks.width as u32, blocks.height as u32)
        });
        let sample = |x: [f64; 3]| Vec3::from(x.map(|v| v as f32));
        for (stats, mean) in batches.pixels.iter_mut().zip(&blocks.mean) {
            stats.add(sample(*mean));
        }
        if let Some(images) = batches.iteration_means.as_mut() {
            images.add(sample(blocks.grand_mean().0));
        }
    }
    MeanImage::from_film(&batches.expect("at least one iteration"))
}

/// Welch per block and channel of two block images, and the ratio b / a of two image means
/// (each with its standard error).
fn compare(
    a: &MeanImage,
    b: &MeanImage,
    (ma, sa): ([f64; 3], [f64; 3]),
    (mb, sb): ([f64; 3], [f64; 3]),
) -> Parity {
    let report = welch_blocks(a, b, 0.01);
    let ratio = [0, 1, 2].map(|c| mb[c] / ma[c]);
    let ratio_se =
        [0, 1, 2].map(|c| ratio[c] * ((sa[c] / ma[c]).powi(2) + (sb[c] / mb[c]).powi(2)).sqrt());
    Parity {
        rejected: report.rejected,
        tests: report.tests,
        smallest_p: report.smallest_p,
        largest_t: report.largest_t,
        ratio,
        ratio_se,
        ratio_z: [0, 1, 2].map(|c| (ratio[c] - 1.0) / ratio_se[c]),
    }
}
