//! Experiment (not committed): unbiased adaptive sampling by rounds with fixed weights, path
//! tracing on the CPU. Prints relMSE of uniform and adaptive at equal total samples.
use hexray::analysis::compare::{compare, read_image};
use hexray::cpu::path_wavefront::trace_pixels;
use hexray::film::output::RgbImage;
use hexray::film::PixelStats;
use hexray::layout::FlatScene;
use hexray::math::sampling::SamplerKind;
use hexray::scene::Scene;
use hexray::transport::camera::Camera;
use hexray::transport::faults::Faults;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene_name = &args[1];
    let reference = &args[2];
    let rounds: u32 = args.get(3).map_or(8, |s| s.parse().unwrap());
    let per_round: u32 = args.get(4).map_or(8, |s| s.parse().unwrap());
    let seed: u32 = args.get(5).map_or(1, |s| s.parse().unwrap());
    let scene = Scene::load(Path::new(&format!("scenes/{scene_name}.json"))).unwrap();
    let flat = FlatScene::build(&scene);
    let (w, h) = (256u32, 256u32);
    let camera = Camera::new(&scene.desc.camera, w, h);
    let reference = read_image(Path::new(reference)).unwrap();
    let npix = (w * h) as usize;
    let all: Vec<(u32, u32, u32)> = (0..h).flat_map(|y| (0..w).map(move |x| (y * w + x, x, y))).collect();
    // samples of `pixels` (first[p], count[p]) into fresh stats
    let run = |counts: &[u32], firsts: &[u32]| -> Vec<PixelStats> {
        let mut groups: BTreeMap<(u32, u32), Vec<usize>> = BTreeMap::new();
        for p in 0..npix {
            if counts[p] > 0 {
                groups.entry((firsts[p], counts[p])).or_default().push(p);
            }
        }
        let jobs: Vec<((u32, u32), Vec<usize>)> = groups
            .into_iter()
            .flat_map(|(k, v)| v.chunks(256).map(|c| (k, c.to_vec())).collect::<Vec<_>>())
            .collect();
        let results: Vec<(Vec<usize>, Vec<PixelStats>)> = jobs
            .into_par_iter()
            .map(|((first, count), ps)| {
                let pixels: Vec<(u32, u32, u32)> = ps.iter().map(|&p| all[p]).collect();
                let mut stats = vec![PixelStats::default(); ps.len()];
                let mut rays = 0;
                trace_pixels(&flat, &camera, &pixels, SamplerKind::Independent, seed, first, count, 1, Faults::NONE, &mut stats, &mut rays);
                (ps, stats)
            })
            .collect();
        let mut out = vec![PixelStats::default(); npix];
        for (ps, st) in results {
            for (p, s) in ps.into_iter().zip(st) {
                out[p] = s;
            }
        }
        out
    };
    let relmse = |img: Vec<[f32; 3]>| {
        let im = RgbImage { width: w as usize, height: h as usize, pixels: img };
        compare(&im, &reference, None).unwrap().relmse
    };
    let total = rounds * per_round;
    // Uniform.
    let t = std::time::Instant::now();
    let uni = run(&vec![total; npix], &vec![0; npix]);
    let t_uni = t.elapsed().as_secs_f64();
    let img_uni: Vec<[f32; 3]> = uni.iter().map(|p| p.mean().map(|x| x as f32)).collect();
    // Adaptive: round budgets 4,4,8,16,32 (sum 64 when total = 64), weights ∝ budget (fixed in
    // advance); counts: a floor of FLOOR x the budget, the rest ∝ need from earlier rounds.
    let floor: f64 = std::env::var("FLOOR").ok().and_then(|v| v.parse().ok()).unwrap_or(0.5);
    let t = std::time::Instant::now();
    let budgets: Vec<u32> = {
        let mut b = vec![total / 16, total / 16];
        let mut x = total / 8;
        while b.iter().sum::<u32>() < total {
            b.push(x);
            x *= 2;
        }
        b
    };
    let sum_b: u32 = budgets.iter().sum();
    let mut next = vec![0u32; npix];
    let mut pooled = vec![PixelStats::default(); npix];
    let mut round_mean_sum = vec![[0f64; 3]; npix];
    for (r, &br) in budgets.iter().enumerate() {
        let counts: Vec<u32> = if r == 0 {
            vec![br; npix]
        } else {
            let need: Vec<f64> = pooled
                .iter()
                .map(|p| {
                    let (m, v) = (p.mean(), p.var_of_mean());
                    let n = p.n.max(1) as f64;
                    (0..3).map(|c| (v[c] * n).sqrt() / (m[c] * m[c] + 0.01).sqrt()).sum::<f64>() / 3.0
                })
                .collect();
            // A box blur of radius BLUR over the image: noise is spatially coherent (caustics).
            let radius: i64 = std::env::var("BLUR").ok().and_then(|v| v.parse().ok()).unwrap_or(0);
            let need: Vec<f64> = if radius == 0 {
                need
            } else {
                let (wi, hi) = (w as i64, h as i64);
                (0..npix)
                    .map(|p| {
                        let (x, y) = (p as i64 % wi, p as i64 / wi);
                        let (mut s, mut k) = (0.0, 0.0);
                        for dy in -radius..=radius {
                            for dx in -radius..=radius {
                                let (xx, yy) = (x + dx, y + dy);
                                if xx >= 0 && yy >= 0 && xx < wi && yy < hi {
                                    s += need[(yy * wi + xx) as usize];
                                    k += 1.0;
                                }
                            }
                        }
                        s / k
                    })
                    .collect()
            };
            let sum_need: f64 = need.iter().sum();
            let fl = (floor * br as f64).max(1.0);
            let rest = br as f64 * npix as f64 - fl * npix as f64;
            need.iter().map(|&n| (fl + (n / sum_need) * rest).round().max(1.0) as u32).collect()
        };
        let st = run(&counts, &next);
        let wr = br as f64 / sum_b as f64;
        for p in 0..npix {
            let m = st[p].mean();
            for c in 0..3 {
                round_mean_sum[p][c] += wr * m[c];
            }
            pooled[p].merge(&st[p]);
            next[p] += counts[p];
        }
    }
    let t_ad = t.elapsed().as_secs_f64();
    let img_ad: Vec<[f32; 3]> = round_mean_sum.iter().map(|s| s.map(|x| x as f32)).collect();
    let img_pooled: Vec<[f32; 3]> = pooled.iter().map(|p| p.mean().map(|x| x as f32)).collect();
    let mean = |img: &Vec<[f32; 3]>| img.iter().map(|p| p[0] as f64).sum::<f64>() / npix as f64;
    println!(
        "{scene_name} seed {seed} {total} spp: uniform relMSE {:.4e} ({t_uni:.2} s) mean {:.5}; adaptive (round means) {:.4e} ({t_ad:.2} s) mean {:.5}; pooled (planted) {:.4e} mean {:.5}",
        relmse(img_uni.clone()), mean(&img_uni), relmse(img_ad.clone()), mean(&img_ad), relmse(img_pooled.clone()), mean(&img_pooled)
    );
}
