//! `hexray bench` is a benchmark, not a test: this only checks that it runs and reports what it
//! promises (one row per scene and backend, positive rates, the warm-up apart, JSON written).

use std::process::Command;

#[test]
fn bench_writes_one_json_row_per_scene_and_backend() {
    let dir = std::env::temp_dir().join(format!("hexray-bench-{}", std::process::id()));
    let out = dir.join("bench.json");
    let status = Command::new(crate::common::hexray_bin())
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["bench", "scenes/cornell_box.json", "scenes/glass_room.json"])
        .args([
            "--backend",
            "cpu",
            "--spp",
            "2",
            "--width",
            "16",
            "--height",
            "16",
        ])
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let rows = report["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for (row, scene) in rows.iter().zip(["cornell_box", "glass_room"]) {
        assert_eq!(row["scene"], scene);
        assert_eq!(row["backend"], "cpu");
        assert_eq!(row["spp"], 2);
        assert!(row["camera_paths_per_second"].as_f64().unwrap() > 0.0);
        // A path traces at least its camera ray.
        assert!(row["rays_per_path"].as_f64().unwrap() >= 1.0);
        assert!(row["warmup_seconds"].as_f64().unwrap() > 0.0);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A row too short to time well says so: a 16x16 render of 2 samples takes milliseconds, and the
/// warning names how many rows and the shortest.
#[test]
fn bench_warns_of_rows_too_short_to_time() {
    let dir = std::env::temp_dir().join(format!("hexray-bench-short-{}", std::process::id()));
    let o = Command::new(crate::common::hexray_bin())
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["bench", "scenes/cornell_box.json", "--backend", "cpu"])
        .args(["--spp", "2", "--width", "16", "--height", "16", "--out"])
        .arg(dir.join("bench.json"))
        .output()
        .unwrap();
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("1 of 1 rows took under 0.25 s") && err.contains("raise --spp"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
