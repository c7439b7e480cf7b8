//! Fuzzing the scene loader: mutated copies of the repository's scenes go through
//! UTF-8 decoding, parsing and validation (`Scene::decode`, `Scene::parse`), and scenes that
//! pass are flattened for rendering. Nothing may panic, and every refusal must be located: a
//! 1-based line and column inside the file, a message and a help line.
//!
//! The mutations: bit flips, deletions, insertions of JSON tokens, numbers replaced with
//! extreme values (1e-46, 1e39, -0, 1e309, ...), values swapped for other types, keys
//! duplicated, truncation. The seed is fixed, so every run tries the same cases.
//!
//! `fuzz_scenes_10k` (10^4 cases) runs with the other tests. The long run is
//! `HEXRAY_FUZZ_CASES=1000000 cargo test --release --test tests fuzz_scenes -- --ignored`
//! (`fuzz_scenes_long`, 10^6 cases by default). Meshes are fuzzed the same way through
//! `mesh::parse` (`fuzz_meshes_*`).

use crate::common::repo;
use hexray::layout::FlatScene;
use hexray::scene::{mesh, MeshDesc, Scene, SceneError};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, RngSeed, TestCaseError, TestRunner};
use std::path::Path;
use std::sync::OnceLock;

/// The seed scenes: every scenes/**/*.json below 64 kB, in sorted order.
fn seeds() -> &'static [Vec<u8>] {
    static SEEDS: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let mut files = Vec::new();
        let mut dirs = vec![repo("scenes")];
        while let Some(d) = dirs.pop() {
            for e in std::fs::read_dir(&d).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    dirs.push(p);
                } else if p.extension().is_some_and(|x| x == "json")
                    && p.metadata().unwrap().len() < 64 << 10
                {
                    files.push(p);
                }
            }
        }
        files.sort();
        assert!(files.len() >= 4, "seed scenes: {files:?}");
        files.iter().map(|p| std::fs::read(p).unwrap()).collect()
    })
}

/// Tokens inserted or swapped in: extreme numbers, other types, broken syntax.
const TOKENS: &[&str] = &[
    "1e-46",
    "1e39",
    "-0",
    "-0.0",
    "1e309",
    "-1e309",
    "5e-324",
    "1.7976931348623157e308",
    "3.4028236e38",
    "1e-30",
    "1e30",
    "0",
    "-1",
    "NaN",
    "\"NaN\"",
    "Infinity",
    "-inf",
    "\"inf\"",
    "null",
    "true",
    "false",
    "\"\"",
    "\"x\"",
    "[]",
    "{}",
    "[[]]",
    "[0, 0]",
    "[0, 0, 0]",
    "[1e39, 0, 0]",
    "[0, 0, 0, 0]",
    "{\"type\": \"diffuse\"}",
    ",",
    ":",
    "[",
    "]",
    "{",
    "}",
    "\"",
    "\\",
    "\\u0000",
    "\u{feff}",
    "\u{1F600}",
    "\u{e9}",
    "\n",
    "\t",
    "//",
    "/*",
    "99999999999999999999",
    "-9223372036854775809",
    "18446744073709551616",
    "0x10",
    "1.",
    ".5",
    "+1",
    "01",
];

/// One change to a scene's bytes; positions are taken modulo the current length.
#[derive(Debug, Clone)]
enum Mutation {
    FlipBit(usize, u8),
    Delete(usize, usize),
    Insert(usize, usize),
    /// Replace the n-th number with a token.
    Number(usize, usize),
    /// Replace the n-th value after a colon (of any type) with a token.
    Swap(usize, usize),
    /// Copy the n-th `"key": value` member in front of itself (a duplicate key).
    DuplicateKey(usize),
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let any = any::<usize>();
    prop_oneof![
        (any, 0u8..8).prop_map(|(p, b)| Mutation::FlipBit(p, b)),
        (any, 1usize..64).prop_map(|(p, n)| Mutation::Delete(p, n)),
        (any, 0..TOKENS.len()).prop_map(|(p, t)| Mutation::Insert(p, t)),
        (any, 0..TOKENS.len()).prop_map(|(p, t)| Mutation::Number(p, t)),
        (any, 0..TOKENS.len()).prop_map(|(p, t)| Mutation::Swap(p, t)),
        any.prop_map(Mutation::DuplicateKey),
        any.prop_map(Mutation::Truncate),
    ]
}

/// Byte ranges of the numbers in `b` (runs of number characters starting with a digit or '-').
fn numbers(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() || b[i] == b'-' {
            let s = i;
            while i < b.len() && matches!(b[i], b'0'..=b'9' | b'-' | b'+' | b'.' | b'e' | b'E') {
                i += 1;
            }
            out.push((s, i));
        } else {
            i += 1;
        }
    }
    out
}

/// The end of the value that starts at `i` (a rough scan: brackets and strings balanced).
fn value_end(b: &[u8], i: usize) -> usize {
    let mut depth = 0i64;
    let mut j = i;
    let mut in_str = false;
    while j < b.len() {
        let c = b[j];
        if in_str {
            if c == b'\\' {
                j += 1;
            } else if c == b'"' {
                in_str = false;
                if depth == 0 {
                    return j + 1;
                }
            }
        } else {
            match c {
                b'"' => in_str = true,
                b'[' | b'{' => depth += 1,
                b']' | b'}' if depth == 0 => return j,
                b']' | b'}' => {
                    depth -= 1;
                    if depth == 0 {
                        return j + 1;
                    }
                }
                b',' if depth == 0 => return j,
                _ => {}
            }
        }
        j += 1;
    }
    b.len()
}

/// Positions of `"key":` (the opening quote) and of the value after its colon.
fn members(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for (i, &c) in b.iter().enumerate() {
        if c == b':' {
            let mut k = i;
            while k > 0 && b[k - 1].is_ascii_whitespace() {
                k -= 1;
            }
            if k > 0 && b[k - 1] == b'"' {
                if let Some(q) = b[..k - 1].iter().rposition(|&c| c == b'"') {
                    let mut v = i + 1;
                    while v < b.len() && b[v].is_ascii_whitespace() {
                        v += 1;
                    }
                    out.push((q, v));
                }
            }
        }
    }
    out
}

fn apply(b: &mut Vec<u8>, m: &Mutation) {
    let len = b.len().max(1);
    match *m {
        Mutation::FlipBit(p, bit) => {
            if !b.is_empty() {
                b[p % len] ^= 1 << bit;
            }
        }
        Mutation::Delete(p, n) => {
            let s = p % len;
            let e = (s + n).min(b.len());
            b.drain(s.min(e)..e);
        }
        Mutation::Insert(p, t) => {
            let s = (p % (b.len() + 1)).min(b.len());
            b.splice(s..s, TOKENS[t].bytes());
        }
        Mutation::Number(n, t) => {
            let nums = numbers(b);
            if !nums.is_empty() {
                let (s, e) = nums[n % nums.len()];
                b.splice(s..e, TOKENS[t].bytes());
            }
        }
        Mutation::Swap(n, t) => {
            let ms = members(b);
            if !ms.is_empty() {
                let (_, v) = ms[n % ms.len()];
                let e = value_end(b, v);
                b.splice(v..e.max(v), TOKENS[t].bytes());
            }
        }
        Mutation::DuplicateKey(n) => {
            let ms = members(b);
            if !ms.is_empty() {
                let (k, v) = ms[n % ms.len()];
                let e = value_end(b, v);
                let mut copy = b[k..e.max(v)].to_vec();
                copy.extend_from_slice(b",\n");
                b.splice(k..k, copy);
            }
        }
        Mutation::Truncate(p) => b.truncate(p % len),
    }
}

/// Loads the bytes as the loader does (less the mesh files) and checks the outcome; true when
/// the scene was refused.
fn check_scene(bytes: &[u8]) -> Result<bool, TestCaseError> {
    let path = Path::new("fuzz.json");
    let result = Scene::decode(bytes, path)
        .and_then(|text| Scene::parse(text, path).map(|desc| (text, desc)));
    match result {
        Ok((text, desc)) => {
            if desc.meshes.is_empty() {
                // Accepted: it must also build for rendering without a panic.
                let scene = Scene::from_json(text, path).map_err(|e| {
                    TestCaseError::fail(format!("parse accepted but from_json refused: {e}"))
                })?;
                let flat = FlatScene::build(&scene, hexray::render::CpuBackend::TRAVERSAL);
                std::hint::black_box(&flat);
            }
            Ok(false)
        }
        Err(e) => check_located(&e, bytes).map(|()| true),
    }
}

fn check_located(e: &SceneError, bytes: &[u8]) -> Result<(), TestCaseError> {
    let shown = e.to_string();
    let Some((line, col)) = e.line_col else {
        return Err(TestCaseError::fail(format!("no line:column: {shown}")));
    };
    let lines = bytes.iter().filter(|&&c| c == b'\n').count() + 1;
    prop_assert!(
        line >= 1 && line <= lines,
        "line {line} of {lines}: {shown}"
    );
    prop_assert!(col >= 1, "column {col}: {shown}");
    prop_assert!(!e.message.trim().is_empty(), "no message: {shown}");
    prop_assert!(!e.help.trim().is_empty(), "no help: {shown}");
    let prefix = format!("fuzz.json:{line}:{col}: ");
    prop_assert!(shown.starts_with(&prefix), "wording: {shown}");
    Ok(())
}

/// The case count: `HEXRAY_FUZZ_CASES` when set, else `default`.
fn cases(default: u32) -> u32 {
    std::env::var("HEXRAY_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

fn config(cases: u32, seed: u64) -> Config {
    Config {
        cases,
        rng_algorithm: RngAlgorithm::ChaCha,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        max_shrink_iters: 2048,
        ..Config::default()
    }
}

/// Runs `cases` mutated scenes with a fixed seed; prints the count and the time.
fn fuzz_scenes(cases: u32) {
    let seeds = seeds();
    let strategy = (0..seeds.len(), prop::collection::vec(mutation(), 1..5));
    let mut runner = TestRunner::new(config(cases, 0x4e58_7261_7916));
    let start = std::time::Instant::now();
    let refused = std::sync::atomic::AtomicU64::new(0);
    let result = runner.run(&strategy, |(seed, muts)| {
        let mut b = seeds[seed].clone();
        for m in &muts {
            apply(&mut b, m);
        }
        if check_scene(&b)? {
            refused.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
        Ok(())
    });
    let secs = start.elapsed().as_secs_f64();
    eprintln!(
        "fuzz_scenes: {cases} cases from {} seed scenes in {secs:.1} s, {} refused",
        seeds.len(),
        refused.into_inner()
    );
    if let Err(e) = result {
        panic!("{e}");
    }
}

#[test]
fn fuzz_scenes_10k() {
    fuzz_scenes(cases(10_000));
}

#[test]
#[ignore = "long: 10^6 cases, run by hand (see the module's documentation)"]
fn fuzz_scenes_long() {
    fuzz_scenes(cases(1_000_000));
}

/// Small meshes: ASCII and binary PLY, OBJ.
fn mesh_seeds() -> Vec<(&'static str, Vec<u8>)> {
    let ascii = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n4 0 1 2 3\n"
        .to_vec();
    let mut binary = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
property float y\nproperty float z\nelement face 1\nproperty list uchar uint vertex_indices\n\
end_header\n"
        .to_vec();
    for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for c in v {
            binary.extend_from_slice(&c.to_le_bytes());
        }
    }
    binary.push(3);
    for i in 0u32..3 {
        binary.extend_from_slice(&i.to_le_bytes());
    }
    let obj = b"# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n\
f 1/1/1 2//1 3\nf -4 -3 -2 -1\n"
        .to_vec();
    vec![("m.ply", ascii), ("b.ply", binary), ("m.obj", obj)]
}

fn fuzz_meshes(cases: u32) {
    let seeds = mesh_seeds();
    let strategy = (0..seeds.len(), prop::collection::vec(mutation(), 1..4));
    let mut runner = TestRunner::new(config(cases, 0x6d65_7368));
    let start = std::time::Instant::now();
    let result = runner.run(&strategy, |(seed, muts)| {
        let (name, bytes) = &seeds[seed];
        let mut b = bytes.clone();
        for m in &muts {
            apply(&mut b, m);
        }
        let placed = mesh::parse(name, &b).and_then(|data| {
            let desc: MeshDesc = serde_json::from_value(serde_json::json!({
                "file": name, "material": "m", "scale": 2.0,
                "rotate": {"axis": [0, 0, 1], "degrees": 30}
            }))
            .unwrap();
            mesh::place(&desc, name.into(), &data, &desc.transform())
        });
        if let Err(e) = placed {
            prop_assert!(!e.message.is_empty(), "no message");
        }
        Ok(())
    });
    eprintln!(
        "fuzz_meshes: {cases} cases in {:.1} s",
        start.elapsed().as_secs_f64()
    );
    if let Err(e) = result {
        panic!("{e}");
    }
}

#[test]
fn fuzz_meshes_10k() {
    fuzz_meshes(cases(10_000));
}

#[test]
#[ignore = "long: 10^6 cases, run by hand (see the module's documentation)"]
fn fuzz_meshes_long() {
    fuzz_meshes(cases(1_000_000));
}
