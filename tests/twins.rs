//! One algorithm, two backends: each integrator in `src/cpu/` and its WGSL twin in `shaders/`
//! walk the same numbered steps with the same titles (`// Step 3 - emission: ...`), so that
//! they can be read side by side (docs/design/architecture.md, "CPU files and their WGSL
//! twins").

use crate::common::repo;

/// The integrators and their twins.
const TWINS: [(&str, &str); 6] = [
    ("src/cpu/path.rs", "shaders/path.wgsl"),
    ("src/cpu/light_path.rs", "shaders/light_path.wgsl"),
    ("src/cpu/bdpt.rs", "shaders/bdpt.wgsl"),
    ("src/cpu/whitted.rs", "shaders/whitted.wgsl"),
    ("src/cpu/photon_map.rs", "shaders/photon_map.wgsl"),
    ("src/cpu/radiosity.rs", "shaders/radiosity.wgsl"),
];

/// The steps of a source text, in order: (number, name), the name being the words after
/// `Step N -` up to the first punctuation (what follows says how, in each language's words),
/// read across the comment's wrapped lines.
fn steps(text: &str) -> Vec<(String, String)> {
    // The comments' text, each comment block one line (code lines end a block).
    let mut blocks = Vec::new();
    let mut block = String::new();
    for line in text.lines() {
        // Line comments and doc comments (a step may be a function's, as path tracing's
        // first); not the module's `//!` text.
        let comment = line
            .trim_start()
            .strip_prefix("//")
            .map(|c| c.strip_prefix('/').unwrap_or(c));
        match comment {
            Some(c) if !c.starts_with('!') => {
                block.push(' ');
                block.push_str(c.trim());
            }
            _ => {
                if !block.is_empty() {
                    blocks.push(std::mem::take(&mut block));
                }
            }
        }
    }
    blocks.push(block);
    let mut out = Vec::new();
    for b in &blocks {
        let Some(rest) = b.trim().strip_prefix("Step ") else {
            continue;
        };
        let Some((number, title)) = rest.split_once(" - ") else {
            continue;
        };
        let end = title.find([':', '.', ',', ';', '(']).unwrap_or(title.len());
        let words: Vec<&str> = title[..end].split_whitespace().collect();
        out.push((number.to_string(), words.join(" ")));
    }
    out
}

/// Where two lists of steps differ, as a message; None where they are the same.
fn difference(cpu: &[(String, String)], gpu: &[(String, String)]) -> Option<String> {
    (cpu != gpu).then(|| {
        let show = |s: &[(String, String)]| {
            s.iter()
                .map(|(n, t)| format!("  {n} - {t}"))
                .collect::<Vec<_>>()
                .join("\n")
        };
        format!("CPU:\n{}\nWGSL:\n{}", show(cpu), show(gpu))
    })
}

#[test]
fn every_integrator_and_its_wgsl_twin_take_the_same_steps() {
    for (cpu, gpu) in TWINS {
        let a = steps(&std::fs::read_to_string(repo(cpu)).unwrap());
        let b = steps(&std::fs::read_to_string(repo(gpu)).unwrap());
        assert!(a.len() >= 5, "{cpu}: only {} steps found", a.len());
        if let Some(d) = difference(&a, &b) {
            panic!("{cpu} and {gpu} differ in their steps:\n{d}");
        }
    }
}

/// The check has power: a twin with one step left out, or one step renamed, is rejected.
#[test]
fn the_twin_check_rejects_a_missing_or_renamed_step() {
    let cpu = std::fs::read_to_string(repo("src/cpu/whitted.rs")).unwrap();
    let gpu = std::fs::read_to_string(repo("shaders/whitted.wgsl")).unwrap();
    let a = steps(&cpu);
    let missing = gpu.replace("// Step 3 - emission", "// emission");
    assert!(difference(&a, &steps(&missing)).is_some());
    let renamed = gpu.replace("// Step 3 - emission", "// Step 3 - emitted light");
    assert!(difference(&a, &steps(&renamed)).is_some());
    assert!(difference(&a, &steps(&gpu)).is_none());
}
