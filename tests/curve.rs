//! `hexray curve` on a tiny scene: the error it records falls as samples accumulate, and its
//! charts are images.
//!
//! Statistic: Spearman's rank correlation between spp and relMSE over the waves (1, 2, 4, ...
//! spp, at least 5 of them) is negative. For an unbiased renderer relMSE falls as 1/spp, so
//! over 6+ doublings a non-negative correlation means the error does not fall at all (a
//! renderer that ignored new samples, or a curve measured against the wrong reference).

use crate::common::repo;
use hexray::analysis::curve::spearman;
use std::process::Command;

#[test]
fn curve_relmse_falls_with_spp_and_its_charts_decode() {
    let dir = std::env::temp_dir().join(format!("hexray-curve-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let hexray = || {
        let mut c = Command::new(crate::common::hexray_bin());
        c.current_dir(repo("."));
        c
    };
    // The reference: an independent (other seed), longer render of the same tiny image.
    let reference = dir.join("ref.exr");
    let o = hexray()
        .args([
            "reference",
            "scenes/cornell_box.json",
            "--backend",
            "cpu",
            "--quiet",
        ])
        .args([
            "--width", "24", "--height", "24", "--spp", "4096", "--seed", "99", "--out",
        ])
        .arg(&reference)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        dir.join("ref_var.exr").exists(),
        "a reference carries its variance"
    );

    let out = dir.join("curve");
    let o = hexray()
        .args([
            "curve",
            "scenes/cornell_box.json",
            "--backend",
            "cpu",
            "--time",
            "0.5",
        ])
        .arg("--reference")
        .arg(&reference)
        .arg("--overlay")
        .arg(repo("tests/data/references/mitsuba_curve.csv"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let csv = std::fs::read_to_string(out.join("curve.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    // Counted from the end: the quoted text fields before them may hold commas.
    let spp: Vec<f64> = rows
        .iter()
        .map(|r| r[r.len() - 4].parse().unwrap())
        .collect();
    let relmse: Vec<f64> = rows
        .iter()
        .map(|r| r[r.len() - 1].parse().unwrap())
        .collect();
    assert!(
        rows.len() >= 5,
        "only {} waves in 0.5 s:\n{csv}",
        rows.len()
    );
    let rho = spearman(&spp, &relmse);
    eprintln!("{} waves, Spearman rho(spp, relMSE) = {rho:.3}", rows.len());
    assert!(rho < 0.0, "relMSE does not fall with spp:\n{csv}");

    for chart in ["relmse_vs_seconds", "relmse_vs_spp"] {
        let png = image::open(out.join(format!("{chart}.png"))).unwrap();
        assert!(png.width() > 100 && png.height() > 100);
        let svg = std::fs::read_to_string(out.join(format!("{chart}.svg"))).unwrap();
        assert!(
            svg.starts_with("<svg") && svg.contains("relMSE"),
            "{chart}.svg"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
