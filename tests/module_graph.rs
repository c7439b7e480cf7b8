//! The library's modules form layers, and no module imports one of a layer above its own or
//! takes part in an import circle (docs/design/architecture.md).
//!
//! The graph is read from the source: every `crate::…` path and `super::…` path outside
//! comments, string literals and `#[cfg(test)]` items is an edge from its file's module to the
//! deepest module the path names. A module and its ancestors count as one (a `mod.rs` and its
//! children share private items by design); unit tests may use any layer, as dev-dependencies
//! may. The checker itself is shown to reject a planted circle and a planted upward import.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The layers, low to high. A top-level module of `src/` must be listed; it may import only
/// from modules of lower layers (so `cpu` and `gpu`, on one layer, never import each other).
const LAYERS: &[&[&str]] = &[
    &["scene", "interrupt"],
    &["layout"],
    &["math"],
    &["accel"],
    &["transport"],
    &["flatten"],
    &["film"],
    &["cpu", "gpu"],
    &["render"],
    &["analysis"],
];

/// Module path ("gpu::renderer::iterations") to its source text, for the library's files.
fn library_sources() -> BTreeMap<String, String> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut out = BTreeMap::new();
    let mut stack = vec![src.clone()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().and_then(|e| e.to_str()) != Some("rs") {
                continue;
            }
            let rel = path.strip_prefix(&src).unwrap().with_extension("");
            let mut parts: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            // The binary (main.rs and the command line in cli/) sits above every layer.
            if parts[0] == "main" || parts[0] == "cli" {
                continue;
            }
            if matches!(parts.last().map(String::as_str), Some("mod" | "lib")) {
                parts.pop();
            }
            out.insert(parts.join("::"), std::fs::read_to_string(&path).unwrap());
        }
    }
    out
}

/// The source with comments, string and char literals blanked out (newlines kept).
fn code_only(source: &str) -> String {
    let b = source.as_bytes();
    let mut out = String::with_capacity(source.len());
    let mut i = 0;
    while i < b.len() {
        let rest = &source[i..];
        if rest.starts_with("//") {
            let end = rest.find('\n').unwrap_or(rest.len());
            i += end;
        } else if rest.starts_with("/*") {
            let end = rest.find("*/").map_or(rest.len(), |e| e + 2);
            out.extend(rest[..end].chars().filter(|&c| c == '\n'));
            i += end;
        } else if rest.starts_with("r#\"") || rest.starts_with("r\"") {
            let hashes = rest[1..].chars().take_while(|&c| c == '#').count();
            let close = format!("\"{}", "#".repeat(hashes));
            let body = 2 + hashes;
            let end = rest[body..]
                .find(&close)
                .map_or(rest.len(), |e| body + e + close.len());
            out.extend(rest[..end].chars().filter(|&c| c == '\n'));
            i += end;
        } else if b[i] == b'"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != b'"' {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            out.extend(source[i..j.min(b.len())].chars().filter(|&c| c == '\n'));
            out.push_str("\"\"");
            i = j + 1;
        } else if b[i] == b'\'' && (rest[1..].starts_with("\\") || rest[2..].starts_with('\'')) {
            // A char literal ('x', '\n', '\u{..}'); a lifetime ('a) has no closing quote.
            let end = rest[1..].find('\'').map_or(rest.len(), |e| e + 2);
            let end = if rest[1..].starts_with("\\'") {
                rest[3..].find('\'').map_or(rest.len(), |e| e + 4)
            } else {
                end
            };
            out.push_str("' '");
            i += end;
        } else {
            let c = rest.chars().next().unwrap();
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

/// The code without the items under `#[cfg(test)]` (a test module, a test-only function).
fn without_test_items(code: &str) -> String {
    let mut out = String::new();
    let mut rest = code;
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let item = &rest[at..];
        // The item ends at its `;` or at the brace that closes its first `{`.
        let mut depth = 0usize;
        let mut end = item.len();
        for (k, c) in item.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = k + 1;
                        break;
                    }
                }
                ';' if depth == 0 => {
                    end = k + 1;
                    break;
                }
                _ => {}
            }
        }
        rest = &item[end..];
    }
    out.push_str(rest);
    out
}

/// The paths a module names: `crate::a::b` and `super::a` (made absolute), with `use` groups
/// (`crate::a::{b, c::d}`) expanded.
fn named_paths(module: &str, code: &str) -> Vec<Vec<String>> {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut paths = Vec::new();
    let text = code;
    for root in ["crate::", "super::"] {
        let mut from = 0;
        while let Some(found) = text[from..].find(root) {
            let at = from + found;
            from = at + root.len();
            if at > 0 && text[..at].chars().next_back().is_some_and(ident) {
                continue;
            }
            // The segments after the root, and a brace group if the path opens one.
            let mut segments = Vec::new();
            let mut k = at + root.len();
            loop {
                let seg: String = text[k..].chars().take_while(|&c| ident(c)).collect();
                if seg.is_empty() {
                    break;
                }
                k += seg.len();
                segments.push(seg);
                if text[k..].starts_with("::") {
                    k += 2;
                } else {
                    break;
                }
            }
            let mut base: Vec<String> = match root {
                "crate::" => Vec::new(),
                // `super` of module a::b (a/b.rs) is a, and of module a (a/mod.rs) the root.
                // (Inside a module inline in a file it would be that file's module; such
                // paths resolve to an ancestor here, which counts as the module itself.)
                _ => {
                    let mut m: Vec<String> = module.split("::").map(String::from).collect();
                    m.pop();
                    m
                }
            };
            // `super::super::x`
            while segments.first().map(String::as_str) == Some("super") {
                segments.remove(0);
                base.pop();
            }
            base.extend(segments);
            if text[k..].starts_with('{') {
                let close = matching_brace(&text[k..]).map_or(text.len(), |e| k + e);
                for item in split_group(&text[k + 1..close - 1]) {
                    let mut p = base.clone();
                    p.extend(
                        item.split("::")
                            .map(|s| s.split_whitespace().next().unwrap_or("").to_string())
                            .filter(|s| !s.is_empty() && s != "self" && s != "{"),
                    );
                    paths.push(p);
                }
            } else {
                paths.push(base);
            }
        }
    }
    paths
}

/// The byte index just past the brace that closes the one `s` starts with.
fn matching_brace(s: &str) -> Option<usize> {
    let mut depth = 0usize;
    for (k, c) in s.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return Some(k + 1);
                }
            }
            _ => {}
        }
    }
    None
}

/// The top-level items of a `use` group's inside, nested groups flattened to their prefix.
fn split_group(inside: &str) -> Vec<String> {
    let mut items = Vec::new();
    let mut depth = 0usize;
    let mut current = String::new();
    for c in inside.chars() {
        match c {
            '{' => {
                depth += 1;
            }
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(std::mem::take(&mut current));
                continue;
            }
            _ => {}
        }
        if depth == 0 && c != '}' {
            current.push(c);
        }
    }
    items.push(current);
    items.into_iter().map(|s| s.trim().to_string()).collect()
}

/// The import graph: module to the modules it names (ancestors and descendants left out).
fn import_graph(sources: &BTreeMap<String, String>) -> Graph {
    let mut graph = Graph::new();
    for (module, source) in sources {
        let code = without_test_items(&code_only(source));
        let edges = graph.entry(module.clone()).or_default();
        for path in named_paths(module, &code) {
            // The deepest module the path names.
            let target = (1..=path.len())
                .rev()
                .map(|n| path[..n].join("::"))
                .find(|m| sources.contains_key(m));
            let Some(target) = target else { continue };
            let related = |a: &str, b: &str| a == b || a.starts_with(&format!("{b}::"));
            if !related(module, &target) && !related(&target, module) {
                edges.insert(target);
            }
        }
    }
    graph
}

type Graph = BTreeMap<String, BTreeSet<String>>;

/// The import circles: strongly connected components of more than one module (Tarjan).
fn circles(graph: &Graph) -> Vec<Vec<String>> {
    struct State<'a> {
        graph: &'a Graph,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        found: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a str) {
        let n = s.index.len();
        s.index.insert(v, n);
        s.low.insert(v, n);
        s.stack.push(v);
        s.on_stack.insert(v);
        let graph = s.graph;
        for w in graph.get(v).into_iter().flatten() {
            let w = w.as_str();
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.on_stack.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            loop {
                let w = s.stack.pop().unwrap();
                s.on_stack.remove(w);
                component.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                component.sort();
                s.found.push(component);
            }
        }
    }
    let mut s = State {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        found: Vec::new(),
    };
    for v in graph.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.found
}

/// The edges that break the layering ("from -> to"), and the top-level modules in no layer.
fn layering_faults(graph: &Graph, layers: &[&[&str]]) -> Vec<String> {
    let top = |m: &str| m.split("::").next().unwrap().to_string();
    let rank = |t: &str| layers.iter().position(|l| l.contains(&t));
    let mut faults = Vec::new();
    for (from, targets) in graph {
        let f = top(from);
        let Some(rf) = rank(&f) else {
            if !from.is_empty() {
                faults.push(format!("{f} is in no layer of LAYERS"));
            }
            continue;
        };
        for to in targets {
            let t = top(to);
            if t == f || to.is_empty() {
                continue;
            }
            match rank(&t) {
                Some(rt) if rt < rf => {}
                _ => faults.push(format!("{from} -> {to}")),
            }
        }
    }
    faults.sort();
    faults.dedup();
    faults
}

fn graph_of(files: &[(&str, &str)]) -> Graph {
    let sources: BTreeMap<String, String> = files
        .iter()
        .map(|(m, s)| (m.to_string(), s.to_string()))
        .collect();
    import_graph(&sources)
}

fn library_graph() -> Graph {
    import_graph(&library_sources())
}

#[test]
fn no_module_takes_part_in_an_import_circle() {
    let found = circles(&library_graph());
    assert!(found.is_empty(), "import circles: {found:?}");
}

#[test]
fn every_module_imports_only_from_lower_layers() {
    let faults = layering_faults(&library_graph(), LAYERS);
    assert!(faults.is_empty(), "imports against the layers: {faults:#?}");
}

#[test]
fn the_graph_sees_the_imports_that_exist() {
    // The checks above pass on an empty graph too: the reader must find known imports.
    let graph = library_graph();
    let has = |from: &str, to: &str| graph.get(from).is_some_and(|t| t.contains(to));
    assert!(
        has("cpu::path", "accel::bvh"),
        "{:?}",
        graph.get("cpu::path")
    );
    assert!(has("flatten", "transport::planar_mirror"));
    assert!(has("gpu::renderer", "gpu::bidirectional"));
    assert!(has("gpu::bidirectional", "gpu::frame"));
    assert!(graph.len() > 40, "{} modules", graph.len());
}

#[test]
fn a_planted_circle_is_found() {
    let graph = graph_of(&[
        ("a", "use crate::b::Thing;\n"),
        ("b", "pub fn f() { crate::c::g() }\n"),
        ("c", "use crate::{a::{self, X}, b};\n"),
        ("d", "// use crate::a;\nconst S: &str = \"crate::a\";\n"),
    ]);
    assert_eq!(circles(&graph), vec![vec!["a", "b", "c"]]);
    assert!(
        graph["d"].is_empty(),
        "comments and strings are not imports"
    );
}

#[test]
fn a_planted_upward_import_breaks_the_layers() {
    let graph = graph_of(&[
        ("scene", "fn f() { crate::cpu::render() }\n"),
        (
            "cpu",
            "use crate::gpu::Renderer;\nuse super::scene::Scene;\n",
        ),
        ("gpu", "#[cfg(test)]\nmod tests { use crate::cpu::x; }\n"),
        ("newcomer", ""),
    ]);
    assert_eq!(
        layering_faults(&graph, LAYERS),
        [
            "cpu -> gpu",
            "newcomer is in no layer of LAYERS",
            "scene -> cpu"
        ]
    );
}
