//! Work is never lost: a stop by any of the usual signals keeps the samples and
//! exits with 128 + the signal; a stop before the first sample writes nothing; a render can be
//! resumed bit for bit from the film written beside it, and only from its own; checkpoints
//! survive a kill without warning.

use crate::common::repo;
use crate::common::temp_dir;
use hexray::film::output::read_exr;
use std::path::Path;
use std::process::{Command, Output};
use std::time::Duration;

fn hexray() -> Command {
    crate::common::hexray_command()
}

/// A small CPU render of `scene` with `args`, into `out`.
fn render(scene: &Path, out: &Path, args: &[&str]) -> Output {
    hexray()
        .arg("render")
        .arg(scene)
        .args(["--backend", "cpu", "--width", "24", "--height", "16", "-q"])
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

fn resume(exr: &Path, args: &[&str]) -> Output {
    hexray()
        .args(["render", "--backend", "cpu", "-q", "--resume"])
        .arg(exr)
        .args(args)
        .output()
        .unwrap()
}

fn ok(o: &Output) {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// The film's sums (the bytes after its header: the header records the render time).
fn film_body(exr: &Path) -> Vec<u8> {
    let bytes = std::fs::read(exr.with_extension("film")).unwrap();
    let n = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    bytes[16 + n..].to_vec()
}

#[test]
fn a_resumed_render_is_bit_identical_to_one_render_of_the_total() {
    let dir = temp_dir!("resume");
    // bdpt with fewer light subpaths than pixels: the resumed passes trace as many.
    for (method, scene, more) in [
        ("path", "scenes/cornell_box.json", &[][..]),
        ("vcm", "scenes/glass_room.json", &[]),
        ("bdpt", "scenes/glass_room.json", &["--light-paths", "100"]),
    ] {
        let scene = repo(scene);
        let (parts, whole) = (
            dir.join(format!("{method}_parts.exr")),
            dir.join(format!("{method}.exr")),
        );
        let args = |spp| [&["--method", method, "--spp", spp, "--seed", "9"][..], more].concat();
        ok(&render(&scene, &parts, &args("3")));
        ok(&resume(&parts, &["--spp", "5"]));
        ok(&resume(&parts, &["--spp", "8"]));
        ok(&render(&scene, &whole, &args("8")));
        assert!(
            film_body(&parts) == film_body(&whole),
            "{method}: the sums differ"
        );
        let ((a, ma), (b, mb)) = (read_exr(&parts).unwrap(), read_exr(&whole).unwrap());
        assert!(a.pixels == b.pixels, "{method}: the images differ");
        assert_eq!(
            (ma.get("spp"), ma.get("seed")),
            (mb.get("spp"), mb.get("seed"))
        );
    }
}

#[test]
fn resume_refuses_a_changed_scene() {
    let dir = temp_dir!("changed");
    let scene = dir.join("scene.json");
    std::fs::copy(repo("scenes/cornell_box.json"), &scene).unwrap();
    let exr = dir.join("c.exr");
    ok(&render(&scene, &exr, &["--method", "path", "--spp", "2"]));
    let before = std::fs::read(&exr).unwrap();
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, text + "\n").unwrap();
    let o = resume(&exr, &["--spp", "4"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("has changed since the render"));
    assert_eq!(
        std::fs::read(&exr).unwrap(),
        before,
        "the render was touched"
    );
}

#[test]
fn resume_refuses_a_film_from_another_render() {
    let dir = temp_dir!("pair");
    let scene = repo("scenes/cornell_box.json");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    ok(&render(
        &scene,
        &a,
        &["--method", "path", "--spp", "2", "--seed", "1"],
    ));
    ok(&render(
        &scene,
        &b,
        &["--method", "path", "--spp", "2", "--seed", "2"],
    ));
    std::fs::copy(b.with_extension("film"), a.with_extension("film")).unwrap();
    let o = resume(&a, &["--spp", "4"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("come from different renders") && err.contains("seed"),
        "{err}"
    );
}

#[test]
fn resume_takes_the_total_and_refuses_one_below_the_samples_taken() {
    let dir = temp_dir!("total");
    let exr = dir.join("t.exr");
    ok(&render(
        &repo("scenes/cornell_box.json"),
        &exr,
        &["--method", "path", "--spp", "4"],
    ));
    let o = resume(&exr, &["--spp", "3"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("already has 4 samples"));
    ok(&resume(&exr, &["--spp", "6"]));
    assert_eq!(read_exr(&exr).unwrap().1.get("spp"), Some("6"));
    // Settings come from the film: giving them again is refused by the command line.
    let o = resume(&exr, &["--spp", "8", "--seed", "3"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn one_sample_per_pixel_writes_no_variance() {
    let dir = temp_dir!("var1");
    let exr = dir.join("v.exr");
    let o = hexray()
        .args([
            "render",
            "scenes/cornell_box.json",
            "--backend",
            "cpu",
            "--method",
            "path",
        ])
        .args([
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "1",
            "--variance",
            "--out",
        ])
        .arg(&exr)
        .output()
        .unwrap();
    ok(&o);
    assert!(exr.exists() && !dir.join("v_var.exr").exists());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no variance written"));
}

#[cfg(unix)]
fn signal(child: &std::process::Child, name: &str) {
    let kill = Command::new("kill")
        .args([&format!("-{name}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
}

#[cfg(unix)]
#[test]
fn sigterm_and_sighup_end_the_render_with_its_samples_and_status_128_plus_the_signal() {
    let dir = temp_dir!("signals");
    for (name, status) in [("TERM", 143), ("HUP", 129)] {
        let exr = dir.join(format!("{name}.exr"));
        let mut child = hexray()
            .args([
                "render",
                "scenes/tncg15_room.json",
                "--backend",
                "cpu",
                "--time",
                "600",
            ])
            .args(["--width", "64", "--height", "64", "-q", "--out"])
            .arg(&exr)
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(1500));
        signal(&child, name);
        let code = child.wait().unwrap().code();
        assert_eq!(code, Some(status), "exit status after SIG{name}");
        let spp: u64 = read_exr(&exr)
            .unwrap()
            .1
            .get("spp")
            .unwrap()
            .parse()
            .unwrap();
        assert!(spp >= 1, "SIG{name}: no samples kept");
        // The film beside it continues the stopped render.
        let o = resume(&exr, &["--spp", &(spp + 1).to_string()]);
        ok(&o);
    }
}

/// A stop before the first sample (here while the scene is still being read: from a FIFO that
/// is written only after the signal) writes nothing, and an earlier render under that name
/// stays as it was.
#[cfg(unix)]
#[test]
fn a_stop_before_the_first_sample_writes_nothing() {
    use std::io::Write;
    let dir = temp_dir!("zero");
    let exr = dir.join("z.exr");
    ok(&render(
        &repo("scenes/cornell_box.json"),
        &exr,
        &["--method", "path", "--spp", "2"],
    ));
    let before: Vec<Vec<u8>> = ["exr", "png", "film"]
        .iter()
        .map(|e| std::fs::read(exr.with_extension(e)).unwrap())
        .collect();
    let fifo = dir.join("scene.json");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let child = hexray()
        .arg("render")
        .arg(&fifo)
        .args([
            "--backend",
            "cpu",
            "--method",
            "path",
            "--spp",
            "4",
            "--out",
        ])
        .arg(&exr)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    signal(&child, "INT");
    std::thread::sleep(Duration::from_millis(100));
    std::fs::OpenOptions::new()
        .write(true)
        .open(&fifo)
        .unwrap()
        .write_all(&std::fs::read(repo("scenes/cornell_box.json")).unwrap())
        .unwrap();
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(
        err.contains("no samples were taken; nothing written"),
        "{err}"
    );
    for (e, old) in ["exr", "png", "film"].iter().zip(&before) {
        assert_eq!(
            &std::fs::read(exr.with_extension(e)).unwrap(),
            old,
            "{e} was touched"
        );
    }
}

#[cfg(unix)]
#[test]
fn checkpoints_survive_a_kill_without_warning_and_resume() {
    let dir = temp_dir!("checkpoint");
    let exr = dir.join("k.exr");
    let mut child = hexray()
        .args([
            "render",
            "scenes/cornell_box.json",
            "--backend",
            "cpu",
            "--method",
            "path",
        ])
        .args(["--time", "600", "--checkpoint", "0.5"])
        .args(["--width", "64", "--height", "64", "-q", "--out"])
        .arg(&exr)
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(2500));
    signal(&child, "KILL");
    child.wait().unwrap();
    let spp: u64 = read_exr(&exr)
        .unwrap()
        .1
        .get("spp")
        .unwrap()
        .parse()
        .unwrap();
    assert!(spp >= 1, "no checkpoint written");
    ok(&resume(&exr, &["--spp", &(spp + 2).to_string()]));
    assert_eq!(
        read_exr(&exr).unwrap().1.get("spp"),
        Some((spp + 2).to_string().as_str())
    );
}

/// A render stopped without warning between writing its EXR and its film leaves the pair one
/// checkpoint apart (the EXR newer); resuming takes the film, which holds the samples, and
/// goes on rather than refusing the pair as two renders.
#[test]
fn a_pair_cut_between_its_writes_resumes_from_the_film() {
    let dir = temp_dir!("cut-pair");
    let exr = dir.join("k.exr");
    ok(&hexray()
        .args([
            "render",
            "scenes/cornell_box.json",
            "--backend",
            "cpu",
            "--method",
            "path",
        ])
        .args([
            "--spp", "4", "--width", "16", "--height", "16", "-q", "--out",
        ])
        .arg(&exr)
        .output()
        .unwrap());
    let film_at_4 = std::fs::read(exr.with_extension("film")).unwrap();
    ok(&resume(&exr, &["--spp", "6"]));
    // The EXR of 6 spp beside the film of 4: a kill after the EXR's write, before the film's.
    std::fs::write(exr.with_extension("film"), film_at_4).unwrap();
    let o = resume(&exr, &["--spp", "8"]);
    ok(&o);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("resuming from the film"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(read_exr(&exr).unwrap().1.get("spp"), Some("8"));
}

crate::common::on_each_backend! {
    /// A stop under way (a vcm iteration at 512x512 takes about a second on 2 cores and on
    /// lavapipe) drops the iteration it finds whole, so the film holds finished iterations only,
    /// and nothing of the dropped one (its splats) is left to the iterations after it: the
    /// render goes on to the same image as one never stopped (bit for bit on the CPU; on a GPU
    /// within the same-streams allowance of its rounding, `photon_merging.rs`).
    fn a_stop_under_way_drops_the_iteration_whole(backend) {
        use crate::common::Render;
        use hexray::analysis::stats::MeanImage;
        use hexray::transport::method::Method;
        let render = Render::file("scenes/cornell_box.json")
            .size(512, 512)
            .spp(2)
            .seed(9)
            .method(Method::Vcm);
        let (stopped, kept) = render.stopped_under_way(backend, Duration::from_millis(200));
        let whole = render.on(backend);
        eprintln!("{backend:?}: the stopped pass kept {kept} of 2 iterations");
        if backend == crate::common::Backend::Cpu {
            // 200 ms into the first of two iterations of about a second each.
            assert!(kept < 2, "the stop was not seen under way");
        }
        let (a, b) = (MeanImage::from_film(&stopped), MeanImage::from_film(&whole));
        let differ = a
            .mean
            .iter()
            .zip(&b.mean)
            .filter(|(x, y)| {
                (0..3).any(|c| (x[c] - y[c]).abs() > 1e-4 * (x[c].abs() + y[c].abs() + 1e-6))
            })
            .count();
        let allowed = if backend == crate::common::Backend::Cpu { 0 } else { a.mean.len() / 100 };
        assert!(differ <= allowed, "{differ} pixels differ from the render never stopped");
    }
}
