//! The command line as a user meets it: `render` (the default subcommand) writes a linear EXR
//! with its metadata, an sRGB PNG and, on request, the variance EXR; a time budget and Ctrl-C
//! both end the render with the samples taken so far written out.

use crate::common::repo;
use crate::common::temp_dir;
use hexray::film::output::read_exr;
use std::path::PathBuf;
use std::process::Command;

fn hexray() -> Command {
    let mut c = Command::new(crate::common::hexray_bin());
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

#[test]
fn render_writes_exr_png_and_variance_with_metadata() {
    let dir = temp_dir!("render");
    let exr = dir.join("cb.exr");
    let o = hexray()
        .args([
            "render",
            "scenes/cornell_box.json",
            "--backend",
            "cpu",
            "--spp",
            "3",
        ])
        .args([
            "--width",
            "16",
            "--height",
            "12",
            "--seed",
            "42",
            "--variance",
            "--quiet",
        ])
        .arg("--out")
        .arg(&exr)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (image, meta) = read_exr(&exr).unwrap();
    assert_eq!((image.width, image.height), (16, 12));
    let text = std::fs::read(repo("scenes/cornell_box.json")).unwrap();
    let sha1 = sha1_smol::Sha1::from(&text[..]).digest().to_string();
    for (k, v) in [
        ("spp", "3"),
        ("seed", "42"),
        ("backend", "cpu"),
        ("scene_sha1", sha1.as_str()),
        ("hexray_version", env!("CARGO_PKG_VERSION")),
        ("dropped_samples", "0"),
    ] {
        assert_eq!(meta.get(k), Some(v), "metadata {k}");
    }
    let secs: f64 = meta.get("render_seconds").unwrap().parse().unwrap();
    assert!(secs > 0.0);
    let (var, _) = read_exr(&dir.join("cb_var.exr")).unwrap();
    assert!(var
        .pixels
        .iter()
        .all(|p| p.iter().all(|&v| v >= 0.0 && v.is_finite())));
    let png = image::open(dir.join("cb.png")).unwrap();
    assert_eq!((png.width(), png.height()), (16, 12));
}

#[test]
fn render_is_the_default_subcommand() {
    let dir = temp_dir!("default");
    let exr = dir.join("room.exr");
    let o = hexray()
        .args([
            "--backend",
            "cpu",
            "--spp",
            "1",
            "--width",
            "8",
            "--height",
            "8",
            "-q",
        ])
        .arg("--out")
        .arg(&exr)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, meta) = read_exr(&exr).unwrap();
    assert_eq!(meta.get("scene_name"), Some("tncg15_room"));
}

#[test]
fn a_time_budget_ends_the_render_and_keeps_its_samples() {
    let dir = temp_dir!("time");
    let exr = dir.join("t.exr");
    let o = hexray()
        .args([
            "render",
            "scenes/tncg15_room.json",
            "--time",
            "0.5",
            "--width",
            "32",
        ])
        .args(["--height", "32", "-q", "--out"])
        .arg(&exr)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, meta) = read_exr(&exr).unwrap();
    let spp: u32 = meta.get("spp").unwrap().parse().unwrap();
    let secs: f64 = meta.get("render_seconds").unwrap().parse().unwrap();
    assert!(spp >= 1);
    // It stops after the pass that crosses the budget; passes aim at 0.25 s.
    assert!((0.5..5.0).contains(&secs), "rendered for {secs} s");
}

/// Kills the render when dropped, so that a test failing before it signals the render does not
/// leave it running on every core.
#[cfg(unix)]
struct KillOnDrop(std::process::Child);

#[cfg(unix)]
impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Ctrl-C once the render has samples: it ends after the current pass, writes every sample
/// taken, and exits 130. The test waits for the render's first checkpoint (written after two
/// seconds of rendering) rather than a fixed time: start-up (the driver, the kernel's build)
/// differs by machine, and a stop before the first sample rightly writes nothing (on an NVIDIA
/// H100 a fixed 1.5 s came before it). The checkpoint's files are then removed before the signal, so the files read
/// afterwards are those written on it (or by a later checkpoint before it, which would also
/// hold the samples).
#[cfg(unix)]
#[test]
fn ctrl_c_ends_the_render_and_keeps_its_samples() {
    let dir = temp_dir!("ctrlc");
    let exr = dir.join("c.exr");
    let mut child = KillOnDrop(
        hexray()
            .args([
                "render",
                "scenes/tncg15_room.json",
                "--time",
                "600",
                "--checkpoint",
                "2",
                "--width",
                "64",
            ])
            .args(["--height", "64", "-q", "--out"])
            .arg(&exr)
            .spawn()
            .unwrap(),
    );
    let film = dir.join("c.film");
    let waited = std::time::Instant::now();
    while !film.exists() {
        assert!(
            waited.elapsed().as_secs() < 120,
            "no checkpoint within 120 s"
        );
        assert!(
            child.0.try_wait().unwrap().is_none(),
            "the render ended early"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // The film is renamed into place last, after the EXR and PNG.
    for f in ["c.exr", "c.png", "c.film"] {
        std::fs::remove_file(dir.join(f)).unwrap();
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.0.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let status = child.0.wait().unwrap();
    assert_eq!(status.code(), Some(130), "exit status after Ctrl-C");
    let (_, meta) = read_exr(&exr).unwrap();
    let spp: u32 = meta.get("spp").unwrap().parse().unwrap();
    assert!(spp >= 1, "no samples kept");
    assert!(dir.join("c.png").exists());
    assert!(film.exists(), "no film to resume from");
}

/// Where no adapter exists (simulated by asking wgpu for Metal on Linux), `--backend gpu` is a
/// clear error with the install line for lavapipe, exit 2, and no output.
#[test]
fn gpu_backend_without_an_adapter_is_a_clear_error() {
    let dir = temp_dir!("noadapter");
    let exr = dir.join("n.exr");
    let o = hexray()
        .env("WGPU_BACKEND", "metal")
        .args([
            "--backend",
            "gpu",
            "--spp",
            "1",
            "--width",
            "8",
            "--height",
            "8",
            "--out",
        ])
        .arg(&exr)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("apt-get install -y mesa-vulkan-drivers"),
        "{stderr}"
    );
    assert!(!exr.exists());
}

/// The default backend, `auto`, falls back to the CPU and says so in one line.
#[test]
fn auto_backend_falls_back_to_the_cpu_and_says_why() {
    let dir = temp_dir!("auto");
    let exr = dir.join("a.exr");
    let o = hexray()
        .env("WGPU_BACKEND", "metal")
        .args(["--spp", "1", "--width", "8", "--height", "8", "--out"])
        .arg(&exr)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let line = stderr
        .lines()
        .find(|l| l.contains("backend cpu (auto)"))
        .unwrap_or_else(|| panic!("{stderr}"));
    assert!(line.contains("no GPU adapter"), "{line}");
    let (_, meta) = read_exr(&exr).unwrap();
    assert_eq!(meta.get("backend"), Some("cpu"));
}

/// With an adapter (lavapipe in CI), `--backend gpu` renders and records the adapter.
#[test]
fn gpu_backend_renders_and_records_its_adapter() {
    let Some(gpu) = crate::common::gpu() else {
        return;
    };
    let dir = temp_dir!("gpu");
    let exr = dir.join("g.exr");
    let o = hexray()
        .args([
            "--backend",
            "gpu",
            "--spp",
            "2",
            "--width",
            "16",
            "--height",
            "16",
            "-q",
        ])
        .arg("--out")
        .arg(&exr)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, meta) = read_exr(&exr).unwrap();
    assert_eq!(meta.get("backend"), Some("gpu"));
    assert!(meta.get("device").unwrap().contains(&gpu.info.name));
    assert_eq!(meta.get("spp"), Some("2"));
}

/// A GPU render says apart what a session pays once: the adapter and device, the kernel's
/// build, and its first pass (where a driver that compiles at the first dispatch compiles),
/// then the rate of the passes after it.
#[test]
fn a_gpu_render_reports_its_start_up_and_first_pass_apart() {
    if crate::common::gpu().is_none() {
        return;
    }
    let dir = temp_dir!("first_pass");
    let o = hexray()
        .args([
            "--backend",
            "gpu",
            "--method",
            "path",
            "--spp",
            "3",
            "--width",
            "16",
            "--height",
            "16",
        ])
        .arg("--out")
        .arg(dir.join("f.exr"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    for line in [
        "hexray: adapter and device in ",
        "hexray: kernel built in ",
        "first pass 1 spp in ",
        "; the other 2 spp at ",
    ] {
        assert!(err.contains(line), "no {line:?} in:\n{err}");
    }
}

/// A small GPU render with `HEXRAY_PIPELINE_CACHE` set to `cache`: its stderr, after asserting
/// that it succeeded.
fn gpu_render_with_pipeline_cache(cache: &std::ffi::OsStr, out: &std::path::Path) -> String {
    let o = hexray()
        .args(["--backend", "gpu", "--method", "path", "--spp", "1"])
        .args(["--width", "8", "--height", "8", "--out"])
        .arg(out)
        .env("HEXRAY_PIPELINE_CACHE", cache)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    err
}

/// A GPU render keeps its compiled pipelines in a file named by the adapter, and the next render
/// reads it. A file that is not a cache (another driver's, a broken write) is set aside: the
/// render starts an empty cache and writes a good one over it.
#[test]
fn a_gpu_render_keeps_its_pipelines_in_a_cache_file_and_survives_a_broken_one() {
    if crate::common::gpu().is_none() {
        return;
    }
    let dir = temp_dir!("pipeline_cache");
    let cache = dir.join("cache");
    let err = gpu_render_with_pipeline_cache(cache.as_os_str(), &dir.join("a.exr"));
    if err.contains("hexray: pipeline cache: none") {
        eprintln!("the adapter offers no pipeline cache: nothing more to check");
        return;
    }
    let files: Vec<_> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    let good = std::fs::read(&files[0]).unwrap();
    assert!(err.contains(": 0 bytes read"), "{err}");
    let err = gpu_render_with_pipeline_cache(cache.as_os_str(), &dir.join("b.exr"));
    assert!(
        err.contains(&format!(": {} bytes read", good.len())),
        "{err}"
    );
    std::fs::write(&files[0], b"not a pipeline cache").unwrap();
    let err = gpu_render_with_pipeline_cache(cache.as_os_str(), &dir.join("c.exr"));
    assert!(err.contains(": 20 bytes read"), "{err}");
    assert_eq!(std::fs::read(&files[0]).unwrap().len(), good.len());
}

/// `HEXRAY_PIPELINE_CACHE=off` keeps no cache, and a cache that cannot be written costs a
/// warning, not the render.
#[test]
fn a_pipeline_cache_can_be_turned_off_and_an_unwritable_one_is_only_a_warning() {
    if crate::common::gpu().is_none() {
        return;
    }
    let dir = temp_dir!("pipeline_cache_off");
    let err = gpu_render_with_pipeline_cache("off".as_ref(), &dir.join("a.exr"));
    assert!(err.contains("hexray: pipeline cache: none"), "{err}");
    // A file where the cache's folder should be.
    let blocked = dir.join("blocked");
    std::fs::write(&blocked, b"").unwrap();
    let err = gpu_render_with_pipeline_cache(blocked.as_os_str(), &dir.join("b.exr"));
    assert!(dir.join("b.exr").exists());
    assert!(
        err.contains("hexray: pipeline cache: none") || err.contains("not written"),
        "{err}"
    );
}

/// `auto` does not pick a software adapter (lavapipe): it runs the kernel on the same cores as
/// the CPU backend, slower. The line says which adapter it passed over and why.
#[test]
fn auto_backend_prefers_the_cpu_backend_over_a_software_adapter() {
    let Some(g) = crate::common::gpu() else {
        return;
    };
    if g.info.device_type != wgpu::DeviceType::Cpu {
        eprintln!("skipping: the adapter is a hardware GPU");
        return;
    }
    let dir = temp_dir!("auto-software");
    let exr = dir.join("a.exr");
    let o = hexray()
        .args(["--spp", "1", "--width", "8", "--height", "8", "--out"])
        .arg(&exr)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let line = stderr
        .lines()
        .find(|l| l.contains("backend cpu (auto)"))
        .unwrap_or_else(|| panic!("{stderr}"));
    assert!(line.contains(&g.info.name), "{line}");
    let (_, meta) = read_exr(&exr).unwrap();
    assert_eq!(meta.get("backend"), Some("cpu"));
}

fn render_to(out: &std::path::Path) -> std::process::Output {
    hexray()
        .args(["render", "scenes/tncg15_room.json", "--spp", "4"])
        .args(["--width", "8", "--height", "8", "-q", "--out"])
        .arg(out)
        .output()
        .unwrap()
}

/// An output that cannot be written is refused before any rendering, with exit 2 and the path
/// in the message: a file in /proc, a path under a regular file, an existing directory.
#[cfg(unix)]
#[test]
fn an_unwritable_output_is_refused_before_rendering() {
    let dir = temp_dir!("unwritable");
    let file = dir.join("plain");
    std::fs::write(&file, b"x").unwrap();
    let folder = dir.join("folder.exr");
    std::fs::create_dir_all(&folder).unwrap();
    for out in [PathBuf::from("/proc/x.exr"), file.join("x.exr"), folder] {
        let o = render_to(&out);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{}: {stderr}", out.display());
        assert!(stderr.contains(&*out.to_string_lossy()), "{stderr}");
    }
}

/// `.exr` is accepted in any letter case, and the EXR keeps the name given.
#[test]
fn an_output_named_in_capitals_is_written_as_named() {
    let dir = temp_dir!("capitals");
    let out = dir.join("ROOM.EXR");
    let o = render_to(&out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.exists() && dir.join("ROOM.png").exists());
}

/// The default output is named after the scene file, so a copied scene does not overwrite the
/// original's render, and a scene `name` of "../../x" cannot write outside out/.
#[test]
fn the_default_output_is_named_after_the_scene_file() {
    let dir = temp_dir!("stem");
    let mut scene: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(repo("scenes/tncg15_room.json")).unwrap())
            .unwrap();
    let escape = format!("hexray-escape-{}", std::process::id());
    scene["name"] = serde_json::json!(format!("../../{escape}"));
    let copy = dir.join("copy.json");
    std::fs::write(&copy, scene.to_string()).unwrap();
    let o = Command::new(crate::common::hexray_bin())
        .current_dir(&dir)
        .arg("render")
        .arg(&copy)
        .args(["--spp", "1", "--width", "8", "--height", "8", "-q"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("out/copy.exr").exists());
    let outside = dir.join("out").join(format!("../../{escape}.exr"));
    assert!(!outside.exists(), "wrote {}", outside.display());
}

/// A scene path beyond Latin-1 (EXR text attributes are Latin-1) renders and records the path:
/// escaped in the file, read back as it was, never a panic after the render.
#[test]
fn a_scene_path_beyond_latin_1_is_recorded_in_the_exr() {
    let dir = temp_dir!("unicode").join("場景");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("部屋.json");
    std::fs::copy(repo("scenes/tncg15_room.json"), &scene).unwrap();
    let out = dir.join("r.exr");
    let o = hexray()
        .arg("render")
        .arg(&scene)
        .args(["--spp", "1", "--width", "8", "--height", "8", "-q", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, meta) = read_exr(&out).unwrap();
    assert_eq!(meta.get("scene"), Some(&*scene.to_string_lossy()));
}

/// `hexray` run from a folder without the repository's scenes renders the default scene from
/// the copy built into the binary: the output lands in that folder's out/, named for the
/// default scene, with the SHA-1 of the repository's file (the same bytes), and the log says
/// which copy was used. Without the built-in copy this exits 2 ("cannot read the scene file").
#[test]
fn the_default_scene_renders_from_any_folder() {
    let dir = temp_dir!("elsewhere");
    let o = Command::new(crate::common::hexray_bin())
        .current_dir(&dir)
        .args(["render", "--backend", "cpu", "--spp", "1"])
        .args(["--width", "8", "--height", "6", "--threads", "1"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("the copy built into hexray"), "{err}");
    let (_, meta) = read_exr(&dir.join("out/tncg15_room.exr")).unwrap();
    let file = std::fs::read(repo("scenes/tncg15_room.json")).unwrap();
    assert_eq!(
        meta.get("scene_sha1"),
        Some(&*sha1_smol::Sha1::from(&file).digest().to_string())
    );
}
