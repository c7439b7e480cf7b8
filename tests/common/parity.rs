//! The parity statistic of `tests/gpu_parity.rs` for any two films, and renders that several
//! stability tests compare against, rendered once per test binary.

use hexray::cpu::Faults;
use hexray::film::Film;
use hexray::method::Method;
use hexray::stats::{welch_blocks, MeanImage};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

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
    let report = welch_blocks(&a.blocks(8), &b.blocks(8), 0.01);
    let (ma, sa) = a.grand_mean();
    let (mb, sb) = b.grand_mean();
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

type Key = (String, u32, u32, u32, u32, String);
type Cache = Mutex<HashMap<Key, Arc<OnceLock<Arc<Film>>>>>;

/// [`super::render_cpu`], rendered once per test binary for each distinct argument list: the
/// first test that asks renders it, the others wait for it and share the film.
pub fn render_cpu_shared(
    rel: &str,
    width: u32,
    height: u32,
    spp: u32,
    seed: u32,
    faults: Faults,
) -> Arc<Film> {
    render_cpu_method_shared(rel, width, height, spp, seed, Method::Path, faults)
}

/// [`super::render_cpu_method`], shared as [`render_cpu_shared`] is: a render that several
/// tests compare against (their planted faults on the other side) is rendered once.
pub fn render_cpu_method_shared(
    rel: &str,
    width: u32,
    height: u32,
    spp: u32,
    seed: u32,
    method: Method,
    faults: Faults,
) -> Arc<Film> {
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let key = (
        rel.to_string(),
        width,
        height,
        spp,
        seed,
        format!("{method:?} {faults:?}"),
    );
    let cell = CACHE
        .get_or_init(Default::default)
        .lock()
        .unwrap()
        .entry(key)
        .or_default()
        .clone();
    cell.get_or_init(|| {
        Arc::new(super::render_cpu_method(
            rel, width, height, spp, seed, method, faults,
        ))
    })
    .clone()
}
