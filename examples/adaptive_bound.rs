//! The most any per-pixel allocation of samples can gain on an image (`benches/adaptive.sh`).
//!
//!   adaptive_bound REFERENCE.exr EVAL_var.exr PLAN_var.exr R F
//!
//! With σ²_p the variance of pixel p's mean in EVAL (a uniform render), the relMSE of a uniform
//! render is ∝ Σ_p v_p, v_p = Σ_c σ²_{p,c} / (ref²_{p,c} + 0.01). Giving pixel p a share a_p of
//! the samples (mean 1) makes it Σ_p v_p / a_p. The shares come from PLAN, another uniform
//! render with its own seed, as `--adaptive` plans them (its need averaged over a box of
//! half-width R pixels, a floor F spread evenly, the rest ∝ √need), so that the plan does not
//! fit EVAL's own noise. Prints Σ v / a over Σ v: the relMSE of such an allocation over the
//! uniform one at equal samples, without the warm-up that a render spends finding the plan.
use hexray::analysis::compare::read_image;
use std::path::Path;

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    anyhow::ensure!(
        a.len() == 6,
        "usage: adaptive_bound REF EVAL_var PLAN_var R F"
    );
    let reference = read_image(Path::new(&a[1]))?;
    let need_of = |path: &str| -> anyhow::Result<Vec<f64>> {
        let var = read_image(Path::new(path))?;
        anyhow::ensure!(
            var.pixels.len() == reference.pixels.len(),
            "{path}: another size"
        );
        Ok(var
            .pixels
            .iter()
            .zip(&reference.pixels)
            .map(|(v, r)| {
                (0..3)
                    .map(|c| v[c] as f64 / ((r[c] as f64).powi(2) + 0.01))
                    .sum()
            })
            .collect())
    };
    let (eval, plan) = (need_of(&a[2])?, need_of(&a[3])?);
    let (r, floor): (i64, f64) = (a[4].parse()?, a[5].parse()?);
    let (w, h) = (reference.width as i64, reference.height as i64);
    let mut root = vec![0.0; plan.len()];
    for y in 0..h {
        for x in 0..w {
            let (mut s, mut k) = (0.0, 0.0);
            for yy in (y - r).max(0)..=(y + r).min(h - 1) {
                for xx in (x - r).max(0)..=(x + r).min(w - 1) {
                    s += plan[(yy * w + xx) as usize];
                    k += 1.0;
                }
            }
            root[(y * w + x) as usize] = (s / k).sqrt();
        }
    }
    let mean_root = root.iter().sum::<f64>() / root.len() as f64;
    let share = |p: usize| floor + (1.0 - floor) * root[p] / mean_root;
    let adaptive: f64 = eval.iter().enumerate().map(|(p, v)| v / share(p)).sum();
    println!("{:.3}", adaptive / eval.iter().sum::<f64>());
    Ok(())
}
