//! Bad input is refused before anything is rendered: each broken scene gives its own error,
//! naming the file, the line:column and the JSON path of the problem and saying what to do; the
//! exit status is 2; no output file is created, and an existing one is not touched.

use crate::common::repo;
use crate::common::temp_dir;
use serde_json::{json, Value};
use std::path::Path;
use std::process::{Command, Output};

struct Case {
    name: &'static str,
    /// The base scene and how to break it.
    base: &'static str,
    edit: fn(&mut Value),
    /// The JSON path the error must name.
    path: &'static str,
    /// Words the message must contain.
    message: &'static str,
    /// Text that must be on the line the error points to (None: no line check).
    on_line: Option<&'static str>,
}

const ROOM: &str = "scenes/tncg15_room.json";
const GLASS: &str = "scenes/glass_room.json";

fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "misspelt material name",
            base: ROOM,
            edit: |s| s["triangles"][3]["material"] = json!("rde"),
            path: "triangles[3].material",
            message: "unknown material `rde`",
            on_line: Some("\"rde\""),
        },
        Case {
            name: "unknown material type",
            base: ROOM,
            edit: |s| s["materials"]["red"]["type"] = json!("difuse"),
            path: "materials.red.type",
            message: "unknown variant `difuse`",
            on_line: Some("difuse"),
        },
        Case {
            name: "field of another material type",
            base: ROOM,
            edit: |s| s["materials"]["mirror"]["albedo"] = json!([0.5, 0.5, 0.5]),
            path: "materials.mirror.albedo",
            message: "unknown field `albedo`",
            on_line: Some("\"albedo\""),
        },
        Case {
            name: "emitting sphere of zero area in f32",
            base: ROOM,
            edit: |s| {
                s["spheres"][0]["material"] = json!("light");
                s["spheres"][0]["radius"] = json!(1e-30);
            },
            path: "spheres[0].radius",
            message: "in f32, too small to sample",
            on_line: Some("1e-30"),
        },
        Case {
            name: "number beyond f32",
            base: ROOM,
            edit: |s| s["triangles"][12]["v"][1][2] = json!(1e39),
            path: "triangles[12].v[1][2]",
            message: "not a finite 32-bit float",
            on_line: Some("e+39"),
        },
        Case {
            name: "zero-area triangle",
            base: ROOM,
            edit: |s| s["triangles"][5]["v"][2] = s["triangles"][5]["v"][0].clone(),
            path: "triangles[5].v",
            message: "zero area",
            on_line: Some("\"v\""),
        },
        Case {
            name: "triangle that collapses in f32 far from the origin",
            base: ROOM,
            // Area 0.2 in f64, but 1e7 + 0.4 rounds to 1e7 in f32 (ulp 1): two vertices merge.
            edit: |s| {
                s["triangles"][5]["v"] =
                    json!([[1e7, 0.0, 0.0], [1.00000004e7, 0.0, 0.0], [1e7, 1.0, 0.0]])
            },
            path: "triangles[5].v",
            message: "zero area at f32 precision",
            on_line: Some("\"v\""),
        },
        Case {
            name: "zero radius",
            base: ROOM,
            edit: |s| s["spheres"][0]["radius"] = json!(0.0),
            path: "spheres[0].radius",
            message: "radius 0 is not > 0",
            on_line: Some("\"radius\""),
        },
        Case {
            name: "negative index of refraction",
            base: GLASS,
            edit: |s| s["materials"]["glass_clear"]["ior"] = json!(-1.5),
            path: "materials.glass_clear.ior",
            message: "index of refraction -1.5",
            on_line: Some("-1.5"),
        },
        Case {
            name: "albedo above 1",
            base: ROOM,
            edit: |s| s["materials"]["red"]["albedo"][0] = json!(1.5),
            path: "materials.red.albedo[0]",
            message: "albedo 1.5 is outside [0, 1]",
            on_line: Some("1.5"),
        },
        Case {
            name: "negative reflectance",
            base: ROOM,
            edit: |s| s["materials"]["mirror"]["reflectance"][1] = json!(-0.1),
            path: "materials.mirror.reflectance[1]",
            message: "reflectance -0.1 is outside [0, 1]",
            on_line: Some("-0.1"),
        },
        Case {
            name: "no emitter",
            base: ROOM,
            edit: |s| {
                for t in s["triangles"].as_array_mut().unwrap() {
                    if t["material"] == "light" {
                        t["material"] = json!("white");
                    }
                }
            },
            path: "triangles",
            message: "no emitter",
            on_line: Some("\"triangles\""),
        },
        Case {
            name: "up parallel to the view",
            base: ROOM,
            edit: |s| s["camera"]["up"] = json!([2, 0, 0]),
            path: "camera.up",
            message: "parallel to the view",
            on_line: Some("\"up\""),
        },
        Case {
            name: "field of view of 180 degrees",
            base: ROOM,
            edit: |s| s["camera"]["vfov_deg"] = json!(180.0),
            path: "camera.vfov_deg",
            message: "outside (0, 180)",
            on_line: Some("180"),
        },
        Case {
            name: "field of view of 0 degrees",
            base: ROOM,
            edit: |s| s["camera"]["vfov_deg"] = json!(0.0),
            path: "camera.vfov_deg",
            message: "outside (0, 180)",
            on_line: Some("\"vfov_deg\""),
        },
        Case {
            name: "misspelt field",
            base: ROOM,
            edit: |s| s["triangles"][0]["colour"] = json!("red"),
            path: "triangles[0].colour",
            message: "unknown field `colour`",
            on_line: Some("colour"),
        },
        Case {
            name: "missing field",
            base: ROOM,
            edit: |s| {
                s["camera"].as_object_mut().unwrap().remove("eye");
            },
            path: "camera",
            message: "missing field `eye`",
            on_line: None,
        },
        // Values valid in f64 that the renderer, in f32, cannot carry: each must be refused
        // with its path (else it would panic, or drop every sample with exit 0).
        Case {
            name: "radiance that is 0 in f32",
            base: ROOM,
            edit: |s| s["materials"]["light"]["radiance"] = json!([1e-46, 20, 20]),
            path: "materials.light.radiance[0]",
            message: "is outside [1e-30, 1e30]",
            on_line: Some("1e-46"),
        },
        Case {
            name: "radiance that overflows a path's throughput",
            base: ROOM,
            edit: |s| s["materials"]["light"]["radiance"] = json!([20, 1.2e38, 20]),
            path: "materials.light.radiance[1]",
            message: "is outside [1e-30, 1e30]",
            on_line: None,
        },
        Case {
            name: "emitter vertices whose squared distances overflow f32",
            base: ROOM,
            edit: |s| s["triangles"][20]["v"][1] = json!([4e18, 1e18, 4.99]),
            path: "triangles[20].v[1][0]",
            message: "where squared distances overflow",
            on_line: None,
        },
        Case {
            name: "emitter whose area is 0 in f32",
            base: ROOM,
            edit: |s| s["triangles"][20]["v"] = json!([[0, 0, 0], [1e-25, 0, 0], [0, 1e-25, 0]]),
            path: "triangles[20].v",
            message: "has area 0e0 in f32",
            on_line: None,
        },
        Case {
            name: "two-sided emitter",
            base: ROOM,
            edit: |s| s["materials"]["light"]["one_sided"] = json!(false),
            path: "materials.light.one_sided",
            message: "two-sided emitters are not modelled",
            on_line: Some("false"),
        },
    ]
}

fn hexray(args: &[&str]) -> Output {
    Command::new(crate::common::hexray_bin())
        .args(args)
        .output()
        .expect("running hexray")
}

/// Runs hexray on `scene_text` with outputs in an empty folder that holds one old PNG; checks the
/// exit status, that the old PNG is untouched and that nothing else appeared. Returns stderr.
fn run_refused(tag: &str, scene_text: &str) -> (String, std::path::PathBuf) {
    let dir = temp_dir!(tag);
    let file = dir.join("scene.json");
    std::fs::write(&file, scene_text).unwrap();
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("x.png"), b"old").unwrap();
    let exr = out.join("x.exr");
    let o = hexray(&[
        "render",
        file.to_str().unwrap(),
        "--out",
        exr.to_str().unwrap(),
        "--spp",
        "1",
        "--width",
        "8",
        "--height",
        "8",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(
        o.status.code(),
        Some(2),
        "{tag}: exit status; stderr:\n{stderr}"
    );
    let files: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        files,
        vec![std::ffi::OsString::from("x.png")],
        "{tag}: outputs appeared"
    );
    assert_eq!(
        std::fs::read(out.join("x.png")).unwrap(),
        b"old",
        "{tag}: old output touched"
    );
    (stderr, file)
}

#[test]
fn every_broken_scene_gets_its_own_located_error_and_exit_2() {
    for case in cases() {
        let mut scene: Value =
            serde_json::from_str(&std::fs::read_to_string(repo(case.base)).unwrap()).unwrap();
        (case.edit)(&mut scene);
        let text = serde_json::to_string_pretty(&scene).unwrap();
        let (stderr, file) = run_refused(&case.name.replace(' ', "_"), &text);

        // "error: FILE:LINE:COL: PATH: MESSAGE" then "  help: ..."
        let first = stderr.lines().next().unwrap_or("");
        let prefix = format!("error: {}:", file.display());
        assert!(first.starts_with(&prefix), "{}: {first}", case.name);
        let rest = &first[prefix.len()..];
        let mut parts = rest.splitn(3, ':');
        let line: usize = parts
            .next()
            .unwrap()
            .parse()
            .unwrap_or_else(|_| panic!("{}: no line in {first}", case.name));
        let col: usize = parts
            .next()
            .unwrap()
            .trim()
            .parse()
            .unwrap_or_else(|_| panic!("{}: no column in {first}", case.name));
        let tail = parts.next().unwrap().trim_start();
        assert!(
            tail.starts_with(&format!("{}: ", case.path)),
            "{}: path in {first}",
            case.name
        );
        assert!(
            first.contains(case.message),
            "{}: message in {first}",
            case.name
        );
        assert!(
            stderr.contains("help: "),
            "{}: no help in {stderr}",
            case.name
        );
        if let Some(token) = case.on_line {
            let text_line = text.lines().nth(line - 1).unwrap_or("");
            assert!(
                text_line.contains(token),
                "{}: line {line} is `{text_line}`, expected it to contain `{token}`",
                case.name
            );
            assert!(
                col >= 1 && col <= text_line.chars().count() + 1,
                "{}: column {col}",
                case.name
            );
        }
    }
}

#[test]
fn a_misspelt_material_suggests_the_closest_name() {
    let mut scene: Value =
        serde_json::from_str(&std::fs::read_to_string(repo(ROOM)).unwrap()).unwrap();
    scene["triangles"][0]["material"] = json!("magneta");
    let (stderr, _) = run_refused("suggest", &serde_json::to_string_pretty(&scene).unwrap());
    assert!(stderr.contains("did you mean `magenta`?"), "{stderr}");
}

#[test]
fn a_json_syntax_error_points_at_the_place() {
    let text = std::fs::read_to_string(repo(ROOM)).unwrap();
    let broken = text.replacen("\"vfov_deg\": 90.0,", "\"vfov_deg\": 90.0,,", 1);
    let (stderr, file) = run_refused("syntax", &broken);
    let line_no = broken.lines().position(|l| l.contains("90.0,,")).unwrap() + 1;
    assert!(
        stderr.contains(&format!("{}:{line_no}:", file.display())),
        "{stderr}"
    );
}

#[test]
fn a_missing_scene_file_is_a_clear_error() {
    let (stderr, _) = {
        let dir = temp_dir!("missing");
        let o = hexray(&[
            "render",
            dir.join("nope.json").to_str().unwrap(),
            "--out",
            dir.join("x.exr").to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2));
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        (String::from_utf8_lossy(&o.stderr).into_owned(), ())
    };
    assert!(
        stderr.contains("nope.json") && stderr.contains("cannot read"),
        "{stderr}"
    );
}

#[test]
fn bad_arguments_exit_2_before_rendering() {
    let dir = temp_dir!("args");
    let exr = dir.join("x.exr");
    let scene = repo(ROOM);
    for args in [
        vec!["--spp", "0"],
        vec!["--time", "-1"],
        vec!["--width", "0"],
        vec!["--backend", "quantum"],
        vec!["--out", "x.png"],
        vec!["--exposure", "NaN"],
        vec!["--exposure", "inf"],
        vec!["--checkpoint", "0"],
        vec!["--light-paths", "0"],
        vec!["--target-error", "0"],
        vec!["--target-error", "-1e-3"],
        vec!["--method", "path", "--light-paths", "1000"],
    ] {
        let mut all = vec![
            "render",
            scene.to_str().unwrap(),
            "--out",
            exr.to_str().unwrap(),
        ];
        all.extend(args.iter());
        let o = hexray(&all);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(!Path::new(&exr).exists() && !Path::new("x.png").exists());
    }
}

#[test]
fn a_scene_file_beyond_the_size_limit_is_refused_without_reading_it_all() {
    let o = hexray(&["render", "/dev/zero", "--out", "/tmp/hexray-never.exr"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("larger than 256 MiB"), "{err}");
}

#[test]
fn invalid_utf8_is_located() {
    let dir = temp_dir!("utf8");
    let scene = dir.join("s.json");
    std::fs::write(&scene, b"{\n  \"name\": \"caf\xe9\"\n}").unwrap();
    let o = hexray(&["render", scene.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("s.json:2:15") && err.contains("not valid UTF-8"),
        "{err}"
    );
}

#[test]
fn an_image_too_large_for_memory_is_refused_before_allocating() {
    let scene = repo(ROOM);
    let o = hexray(&[
        "render",
        scene.to_str().unwrap(),
        "--width",
        "16384",
        "--height",
        "16384",
        "--out",
        "/tmp/hexray-never.exr",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("GiB of memory"), "{err}");
}

#[test]
fn radiance_beyond_the_splat_range_is_refused_for_the_splatting_methods_only() {
    let dir = temp_dir!("splat");
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(repo(ROOM)).unwrap()).unwrap();
    v["materials"]["light"]["radiance"] = json!([1e12, 1e12, 1e12]);
    let scene = dir.join("bright.json");
    std::fs::write(&scene, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let exr = dir.join("b.exr");
    let run = |method: &str| {
        hexray(&[
            "render",
            scene.to_str().unwrap(),
            "--method",
            method,
            "--backend",
            "cpu",
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "2",
            "-q",
            "--out",
            exr.to_str().unwrap(),
        ])
    };
    for m in ["light", "bdpt", "sppm", "vcm"] {
        let o = run(m);
        assert_eq!(o.status.code(), Some(2), "{m}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("materials.light.radiance[0]") && err.contains("fixed point"),
            "{err}"
        );
        assert!(!exr.exists());
    }
    let o = run("path");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Parser gaps: what serde would accept silently is refused through the CLI as any other
/// bad scene, exit 2 and `FILE:LINE:COL: PATH: message` with a help line.
#[test]
fn trailing_content_duplicates_and_positional_arrays_are_refused_with_a_location() {
    let text = std::fs::read_to_string(repo(ROOM)).unwrap();
    let mut positional: Value = serde_json::from_str(&text).unwrap();
    let c = positional["camera"].clone();
    positional["camera"] = json!([c["eye"], c["look_at"], c["up"], c["vfov_deg"]]);
    for (tag, broken, located) in [
        ("trailing", format!("{}\n{{}}\n", text.trim_end()), ""),
        (
            "duplicate_material",
            text.replacen(
                "\"red\": {",
                "\"red\": {\"type\": \"diffuse\", \"albedo\": [0, 0, 0]},\n  \"red\": {",
                1,
            ),
            "materials.red: duplicate material name `red`",
        ),
        (
            "positional",
            serde_json::to_string_pretty(&positional).unwrap(),
            "camera: expected an object with named fields",
        ),
    ] {
        let (stderr, file) = run_refused(tag, &broken);
        let first = stderr.lines().next().unwrap_or("");
        let prefix = format!("error: {}:", file.display());
        assert!(first.starts_with(&prefix), "{tag}: {stderr}");
        let mut parts = first[prefix.len()..].splitn(3, ':');
        let line: usize = parts.next().unwrap().parse().expect("line");
        let col: usize = parts.next().unwrap().parse().expect("column");
        assert!(line >= 1 && col >= 1, "{tag}: {first}");
        assert!(
            parts.next().unwrap().trim_start().starts_with(located),
            "{tag}: {first}"
        );
        assert!(stderr.contains("\n  help: "), "{tag}: {stderr}");
    }
}

#[test]
fn a_scene_with_a_byte_order_mark_is_accepted() {
    let dir = temp_dir!("bom");
    let scene = dir.join("bom.json");
    let text = std::fs::read_to_string(repo(ROOM)).unwrap();
    std::fs::write(&scene, format!("\u{feff}{text}")).unwrap();
    let o = hexray(&["info", scene.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
