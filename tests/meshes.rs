//! Meshes from PLY and OBJ files (`meshes` in the scene format): the same triangles render bit
//! for bit alike whichever file format or inline JSON carries them; a rotation puts the mesh
//! where the closed form says; every defect of a mesh file is refused before rendering with its
//! own located error and exit 2; the BVH over a 10^5-triangle mesh finds exactly what testing
//! every triangle finds in either backend's tree; and the GPU renders the bunny room as the CPU
//! does, and a mesh of over 4096 triangles in a tree of its own.

use crate::common::temp_dir;
use crate::common::*;
use hexray::accel::bvh;
use hexray::layout::{FlatScene, Triangle};
use hexray::math::geometry::{intersect_triangle, Ray};
use hexray::scene::Scene;
use rayon::prelude::*;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const ROOM: &str = "scenes/tncg15_room.json";

fn room() -> Value {
    serde_json::from_str(&std::fs::read_to_string(repo(ROOM)).unwrap()).unwrap()
}

/// A small mesh with a triangle, a quad and a pentagon (fanned into 1 + 2 + 3 triangles), its
/// vertices f32 values (so a float PLY holds them exactly) from a fixed generator.
struct Mesh {
    v: Vec<[f32; 3]>,
    faces: Vec<Vec<u32>>,
}

fn small_mesh() -> Mesh {
    let mut state = 0x2545_f491_u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    };
    let v: Vec<[f32; 3]> = (0..7).map(|_| [next(), next(), next()]).collect();
    Mesh {
        v,
        faces: vec![vec![0, 1, 2], vec![1, 3, 4, 2], vec![2, 4, 5, 6, 0]],
    }
}

fn ply_header(m: &Mesh, format: &str, coord: &str, count: &str, index: &str) -> String {
    format!(
        "ply\nformat {format} 1.0\ncomment test mesh\nelement vertex {}\nproperty {coord} x\n\
         property {coord} y\nproperty {coord} z\nelement face {}\n\
         property list {count} {index} vertex_indices\nend_header\n",
        m.v.len(),
        m.faces.len()
    )
}

/// Binary PLY: little endian with float vertices and uchar/int faces, or big endian with double
/// vertices and int/uint faces.
fn binary_ply(m: &Mesh, little: bool) -> Vec<u8> {
    let mut b = if little {
        ply_header(m, "binary_little_endian", "float", "uchar", "int")
    } else {
        ply_header(m, "binary_big_endian", "double", "int", "uint")
    }
    .into_bytes();
    for v in &m.v {
        for &x in v {
            if little {
                b.extend(x.to_le_bytes());
            } else {
                b.extend((x as f64).to_be_bytes());
            }
        }
    }
    for f in &m.faces {
        if little {
            b.push(f.len() as u8);
            f.iter().for_each(|i| b.extend((*i as i32).to_le_bytes()));
        } else {
            b.extend((f.len() as i32).to_be_bytes());
            f.iter().for_each(|i| b.extend(i.to_be_bytes()));
        }
    }
    b
}

/// ASCII PLY, each coordinate as the shortest decimal of its f64 value (exactly the f32).
fn ascii_ply(m: &Mesh) -> Vec<u8> {
    let mut s = ply_header(m, "ascii", "float", "uchar", "int");
    for v in &m.v {
        s += &format!("{} {} {}\n", v[0] as f64, v[1] as f64, v[2] as f64);
    }
    for f in &m.faces {
        let idx: Vec<String> = f.iter().map(u32::to_string).collect();
        s += &format!("{} {}\n", f.len(), idx.join(" "));
    }
    s.into_bytes()
}

/// OBJ with texture coordinates and normals that are ignored, faces in the `i/t/n`, `i//n`,
/// `i/t` and plain forms, and the last face by negative (relative) indices.
fn obj(m: &Mesh) -> Vec<u8> {
    let mut s = String::from("# test mesh\no thing\n");
    for v in &m.v {
        s += &format!(
            "v {} {} {}\nvt 0.5 0.5\nvn 0 0 1\n",
            v[0] as f64, v[1] as f64, v[2] as f64
        );
    }
    let n = m.v.len() as i64;
    for (k, f) in m.faces.iter().enumerate() {
        let words: Vec<String> = f
            .iter()
            .enumerate()
            .map(|(j, &i)| match (k, j % 4) {
                (2, _) => format!("{}", i as i64 - n),
                (_, 0) => format!("{}/{}/{}", i + 1, i + 1, i + 1),
                (_, 1) => format!("{}//{}", i + 1, i + 1),
                (_, 2) => format!("{}/{}", i + 1, i + 1),
                _ => format!("{}", i + 1),
            })
            .collect();
        s += &format!("usemtl x\nf {}\n", words.join(" "));
    }
    s.into_bytes()
}

const SCALE: [f64; 3] = [0.7, 1.3, 0.9];
const TRANSLATE: [f64; 3] = [7.1, 1.3, -3.3];

/// The room with the mesh file `file`, scaled and translated, in white.
fn room_with_mesh(file: &str) -> Value {
    let mut s = room();
    s["meshes"] =
        json!([{ "file": file, "material": "white", "scale": SCALE, "translate": TRANSLATE }]);
    s
}

fn write_scene(dir: &Path, name: &str, scene: &Value) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, serde_json::to_string_pretty(scene).unwrap()).unwrap();
    p
}

#[test]
fn a_mesh_renders_bit_for_bit_alike_as_binary_ply_ascii_ply_obj_and_inline_triangles() {
    let dir = temp_dir!("formats");
    let m = small_mesh();
    std::fs::create_dir_all(dir.join("models")).unwrap();
    let files: [(&str, Vec<u8>); 4] = [
        ("models/le.ply", binary_ply(&m, true)),
        ("models/be.ply", binary_ply(&m, false)),
        ("models/ascii.ply", ascii_ply(&m)),
        ("models/mesh.obj", obj(&m)),
    ];
    let mut scenes = Vec::new();
    for (name, bytes) in &files {
        std::fs::write(dir.join(name), bytes).unwrap();
        let stem = Path::new(name).file_stem().unwrap().to_str().unwrap();
        scenes.push(write_scene(
            &dir,
            &format!("{stem}.json"),
            &room_with_mesh(name),
        ));
    }
    // The same triangles inline, after the room's: each coordinate (v * s) + t in f64.
    let mut inline = room();
    let place = |v: [f32; 3]| [0, 1, 2].map(|k| (v[k] as f64 * SCALE[k]) + TRANSLATE[k]);
    for f in &m.faces {
        for i in 1..f.len() - 1 {
            inline["triangles"].as_array_mut().unwrap().push(json!({
                "v": [place(m.v[f[0] as usize]), place(m.v[f[i] as usize]), place(m.v[f[i + 1] as usize])],
                "material": "white"
            }));
        }
    }
    scenes.push(write_scene(&dir, "inline.json", &inline));

    let loaded: Vec<Scene> = scenes
        .iter()
        .map(|p| Scene::load(p).unwrap_or_else(|e| panic!("{e}")))
        .collect();
    let flats: Vec<FlatScene> = loaded
        .iter()
        .map(|s| FlatScene::build(s, hexray::render::CpuBackend::TRAVERSAL))
        .collect();
    let bare = FlatScene::build(
        &Scene::load(&repo(ROOM)).unwrap(),
        hexray::render::CpuBackend::TRAVERSAL,
    );
    assert_eq!(flats[0].triangles.len(), bare.triangles.len() + 6);
    let films: Vec<_> = loaded
        .iter()
        .map(|s| {
            Render::scene(s)
                .size(24, 24)
                .spp(2)
                .seed(7)
                .cpu()
                .mean_image()
        })
        .collect();
    let bits =
        |img: &Vec<[f32; 3]>| -> Vec<u32> { img.iter().flatten().map(|x| x.to_bits()).collect() };
    let reference = bits(&films[4]);
    for (k, (p, flat)) in scenes.iter().zip(&flats).enumerate() {
        assert!(
            flat.triangles == flats[4].triangles,
            "{}: triangles differ from inline",
            p.display()
        );
        assert!(flat.nodes == flats[4].nodes, "{}: BVH differs", p.display());
        assert_eq!(
            bits(&films[k]),
            reference,
            "{}: render differs from inline",
            p.display()
        );
    }
    // And the mesh is in the picture: the bare room renders otherwise.
    let bare_scene = Scene::load(&repo(ROOM)).unwrap();
    let bare_film = Render::scene(&bare_scene)
        .size(24, 24)
        .spp(2)
        .seed(7)
        .cpu()
        .mean_image();
    assert_ne!(bits(&bare_film), reference, "the mesh is not visible");
}

/// A box [0, 2] x [0, 1] x [0, 3] as an OBJ of six quads.
const BOX_OBJ: &str = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nv 0 0 3\nv 2 0 3\nv 2 1 3\nv 0 1 3\n\
                       f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

fn mesh_bounds(scene: &Scene) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for t in &scene.meshes[0].triangles {
        for v in t {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k] as f64);
                hi[k] = hi[k].max(v[k] as f64);
            }
        }
    }
    (lo, hi)
}

#[test]
fn a_rotation_moves_the_mesh_bounds_where_the_closed_form_says() {
    let dir = temp_dir!("rotate");
    std::fs::write(dir.join("box.obj"), BOX_OBJ).unwrap();
    let load = |rotate: Value, name: &str| {
        let mut s = room();
        s["meshes"] = json!([{ "file": "box.obj", "material": "white", "scale": 0.5,
                               "rotate": rotate, "translate": [6, 1, -2] }]);
        Scene::load(&write_scene(&dir, name, &s)).unwrap_or_else(|e| panic!("{e}"))
    };
    // 30 degrees about +z: the scaled box [0, 1] x [0, 0.5] x [0, 1.5] turns counter-clockwise;
    // x' = x cos - y sin spans [-0.5 sin, cos], y' = x sin + y cos spans [0, sin + 0.5 cos].
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let (lo, hi) = mesh_bounds(&load(
        json!({ "axis": [0, 0, 2], "degrees": 30 }),
        "z30.json",
    ));
    let want_lo = [6.0 - 0.5 * s, 1.0, -2.0];
    let want_hi = [6.0 + c, 1.0 + s + 0.5 * c, -0.5];
    for k in 0..3 {
        assert!(
            (lo[k] - want_lo[k]).abs() <= 1e-6,
            "min {lo:?} != {want_lo:?}"
        );
        assert!(
            (hi[k] - want_hi[k]).abs() <= 1e-6,
            "max {hi:?} != {want_hi:?}"
        );
    }
    // A quarter turn about -x is exact: (x, y, z) -> (x, z, -y).
    let (lo, hi) = mesh_bounds(&load(
        json!({ "axis": [-1, 0, 0], "degrees": 90 }),
        "x90.json",
    ));
    assert_eq!(lo, [6.0, 1.0, -2.5]);
    assert_eq!(hi, [7.0, 2.5, -2.0]);
    // 120 degrees about [1, 1, 1] permutes the axes: (x, y, z) -> (z, x, y).
    let (lo, hi) = mesh_bounds(&load(
        json!({ "axis": [1, 1, 1], "degrees": 120 }),
        "d120.json",
    ));
    let want_hi = [6.0 + 1.5, 1.0 + 1.0, -2.0 + 0.5];
    for k in 0..3 {
        assert!((lo[k] - [6.0, 1.0, -2.0][k]).abs() <= 1e-6, "min {lo:?}");
        assert!((hi[k] - want_hi[k]).abs() <= 1e-6, "max {hi:?}");
    }
}

fn hexray(args: &[&str]) -> Output {
    Command::new(crate::common::hexray_bin())
        .args(args)
        .output()
        .expect("running hexray")
}

/// A tetrahedron as ASCII PLY, with `vertices` and `faces` lines substituted.
fn tetra_ply(vertices: &str, faces: &str) -> Vec<u8> {
    format!(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
         property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n\
         {vertices}{faces}"
    )
    .into_bytes()
}
const TETRA_V: &str = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
const TETRA_F: &str = "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

fn tetra_binary() -> Vec<u8> {
    let m = Mesh {
        v: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        faces: vec![vec![0, 2, 1], vec![0, 1, 3], vec![0, 3, 2], vec![1, 2, 3]],
    };
    binary_ply(&m, true)
}

/// A binary PLY with its header's face count replaced.
fn with_face_count(ply: &[u8], count: &str) -> Vec<u8> {
    let old = b"element face 4\n";
    let at = ply.windows(old.len()).position(|w| w == old).unwrap();
    let new = format!("element face {count}\n");
    [&ply[..at], new.as_bytes(), &ply[at + old.len()..]].concat()
}

struct Case {
    name: &'static str,
    /// The mesh file's name and bytes (None: not written).
    file: (&'static str, Option<Vec<u8>>),
    /// Changes to the mesh entry of the scene.
    edit: fn(&mut Value),
    path: &'static str,
    message: &'static str,
}

fn cases() -> Vec<Case> {
    let keep = |_: &mut Value| {};
    let binary = tetra_binary();
    vec![
        Case {
            name: "missing file",
            file: ("nope.ply", None),
            edit: keep,
            path: "meshes[0].file",
            message: "cannot read the mesh file",
        },
        Case {
            name: "truncated binary PLY",
            file: ("t.ply", Some(binary[..binary.len() - 6].to_vec())),
            edit: keep,
            path: "meshes[0].file",
            message: "the file ends inside face 3 of 4",
        },
        Case {
            name: "header counts larger than the file",
            file: ("t.ply", Some(with_face_count(&binary, "4000000000"))),
            edit: keep,
            path: "meshes[0].file",
            message: "need at least",
        },
        Case {
            name: "PLY index out of range",
            file: (
                "t.ply",
                Some(tetra_ply(TETRA_V, "3 0 2 1\n3 0 1 3\n3 0 9 2\n3 1 2 3\n")),
            ),
            edit: keep,
            path: "meshes[0].file",
            message: "face 2 (line 16): vertex index 9 is out of range (the file has 4 vertices)",
        },
        Case {
            name: "OBJ index out of range",
            file: (
                "t.obj",
                Some(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n".to_vec()),
            ),
            edit: keep,
            path: "meshes[0].file",
            message: "face 1 (line 5): vertex index 4 is out of range",
        },
        Case {
            name: "OBJ negative index before its vertex",
            file: (
                "t.obj",
                Some(b"v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n".to_vec()),
            ),
            edit: keep,
            path: "meshes[0].file",
            message: "vertex index -3 is out of range",
        },
        Case {
            name: "OBJ index 0",
            file: (
                "t.obj",
                Some(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n".to_vec()),
            ),
            edit: keep,
            path: "meshes[0].file",
            message: "vertex index 0",
        },
        Case {
            name: "NaN vertex in PLY",
            file: (
                "t.ply",
                Some(tetra_ply("0 0 0\n1 0 0\n0 nan 0\n0 0 1\n", TETRA_F)),
            ),
            edit: keep,
            path: "meshes[0].file",
            message: "vertex 2 has a coordinate NaN (not finite)",
        },
        Case {
            name: "infinite vertex in OBJ",
            file: (
                "t.obj",
                Some(b"v 0 0 0\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n".to_vec()),
            ),
            edit: keep,
            path: "meshes[0].file",
            message: "vertex 2 has a coordinate inf (not finite)",
        },
        Case {
            name: "vertex beyond f32 after the scale",
            file: (
                "t.obj",
                Some(b"v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n".to_vec()),
            ),
            edit: |m| m["scale"] = json!(1e10),
            path: "meshes[0].file",
            message: "where squared distances overflow",
        },
        Case {
            name: "PLY face of two vertices",
            file: (
                "t.ply",
                Some(tetra_ply(TETRA_V, "3 0 2 1\n2 0 1\n3 0 3 2\n3 1 2 3\n")),
            ),
            edit: keep,
            path: "meshes[0].file",
            message: "face 1 (line 15) has 2 vertices; a face needs at least 3",
        },
        Case {
            name: "OBJ face of two vertices",
            file: (
                "t.obj",
                Some(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n".to_vec()),
            ),
            edit: keep,
            path: "meshes[0].file",
            message: "face 0 (line 4) has 2 vertices",
        },
        Case {
            name: "every triangle degenerate",
            file: (
                "t.obj",
                Some(b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n".to_vec()),
            ),
            edit: keep,
            path: "meshes[0].file",
            message: "all 1 triangles of the mesh have zero area",
        },
        Case {
            name: "not a mesh format",
            file: ("t.stl", Some(b"solid x\n".to_vec())),
            edit: keep,
            path: "meshes[0].file",
            message: "unknown mesh format",
        },
        Case {
            name: "unknown material",
            file: ("t.ply", Some(tetra_ply(TETRA_V, TETRA_F))),
            edit: |m| m["material"] = json!("whit"),
            path: "meshes[0].material",
            message: "unknown material `whit`",
        },
        Case {
            name: "zero scale",
            file: ("t.ply", Some(tetra_ply(TETRA_V, TETRA_F))),
            edit: |m| m["scale"] = json!([1, 0, 1]),
            path: "meshes[0].scale[1]",
            message: "scale 0 is not a finite nonzero number",
        },
        Case {
            name: "zero rotation axis",
            file: ("t.ply", Some(tetra_ply(TETRA_V, TETRA_F))),
            edit: |m| m["rotate"] = json!({ "axis": [0, 0, 0], "degrees": 10 }),
            path: "meshes[0].rotate.axis",
            message: "the rotation axis is zero",
        },
    ]
}

/// Runs `hexray render` on `scene` with outputs in an empty folder: exit 2 and nothing written.
/// Returns stderr.
fn refused(dir: &Path, scene: &Path) -> String {
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let o = hexray(&[
        "render",
        scene.to_str().unwrap(),
        "--out",
        out.join("x.exr").to_str().unwrap(),
        "--spp",
        "1",
        "--width",
        "8",
        "--height",
        "8",
        "--backend",
        "cpu",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "exit status; stderr:\n{stderr}");
    assert_eq!(
        std::fs::read_dir(&out).unwrap().count(),
        0,
        "outputs appeared: {stderr}"
    );
    stderr
}

#[test]
fn every_bad_mesh_gets_its_own_located_error_exit_2_and_no_output() {
    for case in cases() {
        let dir = temp_dir!(&case.name.replace(' ', "_"));
        let (name, bytes) = &case.file;
        if let Some(b) = bytes {
            std::fs::write(dir.join(name), b).unwrap();
        }
        let mut s = room();
        s["meshes"] = json!([{ "file": name, "material": "white" }]);
        (case.edit)(&mut s["meshes"][0]);
        let text = serde_json::to_string_pretty(&s).unwrap();
        let scene = dir.join("scene.json");
        std::fs::write(&scene, &text).unwrap();
        let stderr = refused(&dir, &scene);
        // "error: FILE:LINE:COL: PATH: MESSAGE" then "  help: ..."
        let first = stderr.lines().next().unwrap_or("");
        let prefix = format!("error: {}:", scene.display());
        assert!(first.starts_with(&prefix), "{}: {first}", case.name);
        let mut parts = first[prefix.len()..].splitn(3, ':');
        let line: usize = parts
            .next()
            .unwrap()
            .parse()
            .unwrap_or_else(|_| panic!("{}: {first}", case.name));
        let _col: usize = parts
            .next()
            .unwrap()
            .parse()
            .unwrap_or_else(|_| panic!("{}: {first}", case.name));
        // The line holds the field (an array element's line is checked by its path alone).
        if !case.path.ends_with(']') {
            let key = case.path.rsplit('.').next().unwrap();
            assert!(
                text.lines()
                    .nth(line - 1)
                    .unwrap_or("")
                    .contains(&format!("\"{key}\"")),
                "{}: line {line} does not hold `{key}`",
                case.name
            );
        }
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
        if case.path == "meshes[0].file" && bytes.is_some() {
            assert!(
                first.contains(&format!("{name}: ")),
                "{}: the mesh file is not named: {first}",
                case.name
            );
        }
    }
}

#[test]
fn a_misspelt_mesh_material_suggests_the_closest_name() {
    let dir = temp_dir!("suggest");
    std::fs::write(dir.join("t.ply"), tetra_ply(TETRA_V, TETRA_F)).unwrap();
    let mut s = room();
    s["meshes"] = json!([{ "file": "t.ply", "material": "magneta" }]);
    let stderr = refused(&dir, &write_scene(&dir, "scene.json", &s));
    assert!(stderr.contains("did you mean `magenta`?"), "{stderr}");
}

#[test]
fn degenerate_mesh_triangles_are_dropped_counted_and_reported() {
    let dir = temp_dir!("degenerate");
    // Face 1 repeats a vertex: zero area. Face 2 is fine.
    std::fs::write(
        dir.join("t.obj"),
        "v 7 0 -4\nv 8 0 -4\nv 7 1 -4\nf 1 2 3\nf 1 2 2\nf 3 2 1\n",
    )
    .unwrap();
    let mut s = room();
    s["meshes"] = json!([{ "file": "t.obj", "material": "white" }]);
    let scene = write_scene(&dir, "scene.json", &s);
    let o = hexray(&["info", scene.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("triangles: 28 (26 inline, 2 from meshes, 0 from boxes)"),
        "{stdout}"
    );
    assert!(
        stdout.contains(
            "3 faces, 2 triangles; dropped 1 triangles of zero area in f32 (the first from face 1)"
        ),
        "{stdout}"
    );
    let out = dir.join("x.exr");
    let o = hexray(&[
        "render",
        scene.to_str().unwrap(),
        "--backend",
        "cpu",
        "--spp",
        "1",
        "--width",
        "8",
        "--height",
        "8",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("dropped 1 triangles of zero area in f32"),
        "{stderr}"
    );
    // The log gives the BVH's build time.
    assert!(
        stderr.contains("hexray: BVH of 29 primitives built in "),
        "{stderr}"
    );
    assert!(out.exists());
}

#[test]
fn info_describes_a_scene_and_refuses_a_bad_one_with_exit_2() {
    let o = hexray(&["info", repo("scenes/bunny_room.json").to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for want in [
        "triangles: 3700 (26 inline, 3674 from meshes, 0 from boxes)",
        "bounds: min [",
        "bvh cpu: ",
        "bvh gpu: ",
        "memory cpu: ",
        "memory gpu: ",
    ] {
        assert!(stdout.contains(want), "no `{want}` in\n{stdout}");
    }
    let dir = temp_dir!("info_bad");
    let mut s = room();
    s["meshes"] = json!([{ "file": "nope.obj", "material": "white" }]);
    let o = hexray(&[
        "info",
        write_scene(&dir, "scene.json", &s).to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("meshes[0].file: cannot read the mesh file")
    );
}

/// The bunny with each triangle cut into n x n (as scenes/models/make_large_mesh.py does, here
/// in f32 directly): 3674 n^2 triangles.
fn cut_bunny(n: u32) -> Vec<Triangle> {
    let bytes = std::fs::read(repo("scenes/models/bunny.ply")).unwrap();
    let m = hexray::scene::mesh::parse("bunny.ply", &bytes).unwrap();
    let mut out = Vec::with_capacity(m.triangles.len() * (n * n) as usize);
    let nf = n as f64;
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let at = |i: u32, j: u32| {
            let (wb, wc) = (i as f64 / nf, j as f64 / nf);
            [0, 1, 2].map(|k| (a[k] + wb * (b[k] - a[k]) + wc * (c[k] - a[k])) as f32)
        };
        for i in 0..n {
            for j in 0..n - i {
                out.push(Triangle::new(at(i, j), at(i + 1, j), at(i, j + 1), 0));
                if i + j < n - 1 {
                    out.push(Triangle::new(
                        at(i + 1, j),
                        at(i + 1, j + 1),
                        at(i, j + 1),
                        0,
                    ));
                }
            }
        }
    }
    out
}

/// Both backends' trees (`bvh::Traversal`).
#[test]
fn the_bvh_finds_what_brute_force_finds_on_a_mesh_of_10_5_triangles() {
    let tris = cut_bunny(6);
    assert!(tris.len() >= 100_000, "{} triangles", tris.len());
    // A fixed generator of uniform numbers in [0, 1).
    let rnd = |i: u32, k: u32| {
        let mut x = (i as u64) << 32 | k as u64;
        x = (x ^ (x >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        x = (x ^ (x >> 27)).wrapping_mul(0x94d049bb133111eb);
        ((x ^ (x >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    // The bunny spans about [-5, 5] x [0, 10] x [-4, 4]: origins in a box around it; half the
    // rays aimed at a random triangle's centroid (they hit), half in random directions.
    let rays: Vec<(Ray, f32)> = (0..1200u32)
        .map(|i| {
            let o = glam::Vec3::new(
                rnd(i, 0) * 16.0 - 8.0,
                rnd(i, 1) * 14.0 - 2.0,
                rnd(i, 2) * 12.0 - 6.0,
            );
            let d = if i % 2 == 0 {
                let t = &tris[(rnd(i, 3) * tris.len() as f32) as usize % tris.len()];
                (glam::Vec3::from(t.v0) + glam::Vec3::from(t.v1) + glam::Vec3::from(t.v2)) / 3.0 - o
            } else {
                glam::Vec3::new(rnd(i, 4), rnd(i, 5), rnd(i, 6)) - 0.5
            };
            (Ray { o, d }, rnd(i, 7) * 1.2)
        })
        .collect();
    // Testing every triangle: each ray's nearest hit, and whether its segment is blocked.
    let truth: Vec<(f32, bool)> = rays
        .par_iter()
        .map(|(ray, t_max)| {
            let hits: Vec<(f32, f32)> = tris
                .iter()
                .filter_map(|t| intersect_triangle(ray, t).map(|h| (h.t, h.t_err)))
                .collect();
            let nearest = hits.iter().map(|h| h.0).fold(f32::INFINITY, f32::min);
            (nearest, hits.iter().any(|&(t, e)| t < t_max - e))
        })
        .collect();
    let hits = truth.iter().filter(|t| t.0.is_finite()).count();
    assert!(hits >= 600, "only {hits} rays hit the mesh");
    for traversal in [bvh::Traversal::Cpu, bvh::Traversal::Shader] {
        let (nodes, prims, wide) = bvh::build_trees(&tris, &[], traversal);
        let scene = FlatScene::from_tree(tris.clone(), Vec::new(), nodes, prims, wide);
        assert_agrees(&scene, &rays, &truth, &format!("{traversal:?}"));
    }
}

/// Every ray's nearest hit and shadow test in `scene` are `truth`'s.
fn assert_agrees(scene: &FlatScene, rays: &[(Ray, f32)], truth: &[(f32, bool)], tree: &str) {
    let disagreements: Vec<String> = rays
        .par_iter()
        .zip(truth)
        .enumerate()
        .filter_map(|(i, ((ray, t_max), &(nearest, blocked)))| {
            let got =
                bvh::intersect_closest(scene, ray, f32::INFINITY).map_or(f32::INFINITY, |h| h.t);
            let got_blocked = bvh::occluded(scene, ray, *t_max);
            (got != nearest || got_blocked != blocked).then(|| {
                format!("ray {i}: closest {got} vs {nearest}, occluded {got_blocked} vs {blocked}")
            })
        })
        .collect();
    assert!(
        disagreements.is_empty(),
        "{tree}: {}",
        disagreements.join("\n")
    );
}

#[test]
fn the_gpu_renders_the_bunny_room_as_the_cpu_does() {
    if gpu().is_none() {
        return;
    }
    assert_gpu_renders_as_cpu(Render::file("scenes/bunny_room.json"), "bunny_room");
}

/// The CPU (seed 1) and the GPU (seed 2) render `render` alike at 32x32 and 64 spp, by the
/// parity test.
fn assert_gpu_renders_as_cpu(render: Render, what: &str) {
    const SIZE: u32 = 32;
    const SPP: u32 = 64;
    let render = render.size(SIZE, SIZE).spp(SPP);
    let a = render.seed(1).cpu();
    let b = render.seed(2).gpu();
    let p = parity::parity(&a, &b);
    eprintln!("{what} at {SPP} spp, {SIZE}x{SIZE}: {p}");
    assert!(p.same(), "{what}: {p}");
}

/// Above 4096 primitives each backend traverses a tree built for it (`bvh::Traversal`): the
/// bunny room with the bunny cut into 14 696 triangles renders alike on both.
#[test]
fn the_gpu_renders_a_mesh_in_its_own_tree_as_the_cpu_does_in_its() {
    if gpu().is_none() {
        return;
    }
    let tris = cut_bunny(2);
    let mesh = Mesh {
        v: tris.iter().flat_map(|t| [t.v0, t.v1, t.v2]).collect(),
        faces: (0..tris.len() as u32)
            .map(|i| vec![3 * i, 3 * i + 1, 3 * i + 2])
            .collect(),
    };
    let dir = temp_dir!("cut_bunny");
    std::fs::write(dir.join("bunny_cut.ply"), binary_ply(&mesh, true)).unwrap();
    let mut desc: Value =
        serde_json::from_str(&std::fs::read_to_string(repo("scenes/bunny_room.json")).unwrap())
            .unwrap();
    desc["meshes"][0]["file"] = json!("bunny_cut.ply");
    let scene = Scene::load(&write_scene(&dir, "scene.json", &desc)).unwrap();
    let cpu_tree = FlatScene::build(&scene, hexray::render::CpuBackend::TRAVERSAL);
    let gpu_tree = FlatScene::build(&scene, hexray::gpu::GpuRenderer::TRAVERSAL);
    assert!(
        gpu_tree.nodes.len() > cpu_tree.nodes.len(),
        "the trees differ: {} and {} nodes",
        cpu_tree.nodes.len(),
        gpu_tree.nodes.len()
    );
    let what = format!("bunny_room cut into {} triangles", tris.len());
    assert_gpu_renders_as_cpu(Render::scene(&scene), &what);
}

#[test]
fn a_scene_array_beyond_the_gpu_binding_limit_is_refused_in_a_sentence() {
    use hexray::gpu::limits::check_scene_fits;
    use hexray::gpu::Residency;
    let (_, flat) = load("scenes/bunny_room.json");
    // bunny_room's 3700 triangles are 0.23 MiB: over a 128 KiB storage binding, under 128 MiB.
    let small = wgpu::Limits {
        max_storage_buffer_binding_size: 128 << 10,
        ..wgpu::Limits::default()
    };
    let e = check_scene_fits(&small, Residency::Storage, &flat).unwrap_err();
    assert!(
        e.contains("the scene's triangles array is 0.2 MiB (3700 triangles)")
            && e.contains("0.125 MiB")
            && e.contains("--backend cpu"),
        "{e}"
    );
    let lavapipe = wgpu::Limits {
        max_storage_buffer_binding_size: 128 << 20,
        ..wgpu::Limits::default()
    };
    assert_eq!(
        check_scene_fits(&lavapipe, Residency::Storage, &flat),
        Ok(())
    );
    // Uniform buffers (64 KiB by default) do not hold it: the storage residency is named.
    let e = check_scene_fits(&lavapipe, Residency::Uniform, &flat).unwrap_err();
    assert!(e.contains("--scene-residency storage"), "{e}");
}

#[test]
fn the_scene_sha1_covers_the_scene_file_and_each_mesh_file() {
    let dir = temp_dir!("sha1");
    let mesh = tetra_ply(TETRA_V, TETRA_F);
    std::fs::write(dir.join("t.ply"), &mesh).unwrap();
    let mut s = room();
    s["meshes"] = json!([{ "file": "t.ply", "material": "white", "translate": [7, 0, -4] }]);
    let path = write_scene(&dir, "scene.json", &s);
    let text = std::fs::read(&path).unwrap();
    let mut want = sha1_smol::Sha1::from(&text);
    want.update(&mesh);
    let first = Scene::load(&path).unwrap().sha1;
    assert_eq!(first, want.digest().to_string());
    // Another vertex in the mesh file, the same scene file: another SHA-1.
    std::fs::write(
        dir.join("t.ply"),
        tetra_ply("0 0 0\n1 0 0\n0 1 0\n0 0 2\n", TETRA_F),
    )
    .unwrap();
    assert_ne!(Scene::load(&path).unwrap().sha1, first);
    // Without meshes it is the SHA-1 of the scene file alone.
    let bare = std::fs::read(repo(ROOM)).unwrap();
    assert_eq!(
        Scene::load(&repo(ROOM)).unwrap().sha1,
        sha1_smol::Sha1::from(&bare).digest().to_string()
    );
}

/// A mesh file is read up to 1 GiB: one that never ends (/dev/zero) is refused, located at its
/// `file`, after reading one byte past the limit, never until memory runs out.
#[test]
fn a_mesh_file_beyond_the_size_limit_is_refused_without_reading_it_all() {
    let dir = temp_dir!("endless");
    let mut s = room();
    s["meshes"] = json!([{ "file": "/dev/zero", "material": "white" }]);
    let stderr = refused(&dir, &write_scene(&dir, "scene.json", &s));
    assert!(
        stderr.contains("meshes[0].file") && stderr.contains("is larger than 1024 MiB"),
        "{stderr}"
    );
}
