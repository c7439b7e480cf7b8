//! Paths into a JSON document (`triangles[12].v[1]`) and where they begin in the text.
//!
//! serde reports where *syntax* goes wrong; a value that parses but makes no sense (a zero-area
//! triangle, a negative radius) is found later, by path. This module turns such a path back into a
//! line and column of the file, so every error points at the text a person has to change.

use std::fmt;

/// One step of a path: an object key or an array index.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Seg {
    Key(String),
    Index(usize),
}

/// A path from the document root, printed as `triangles[12].v[1]`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct JsonPath(pub Vec<Seg>);

impl JsonPath {
    pub fn root() -> Self {
        Self(Vec::new())
    }
    pub fn key(&self, k: &str) -> Self {
        let mut p = self.clone();
        p.0.push(Seg::Key(k.to_string()));
        p
    }
    pub fn index(&self, i: usize) -> Self {
        let mut p = self.clone();
        p.0.push(Seg::Index(i));
        p
    }
}

impl fmt::Display for JsonPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, s) in self.0.iter().enumerate() {
            match s {
                Seg::Key(k) if i == 0 => write!(f, "{k}")?,
                Seg::Key(k) => write!(f, ".{k}")?,
                Seg::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

/// The 1-based line and column where the value at `path` begins, or None if the path is not in
/// the text (then the caller reports the path alone).
pub fn locate(text: &str, path: &JsonPath) -> Option<(usize, usize)> {
    let bytes = text.as_bytes();
    let pos = find(bytes, 0, &path.0)?;
    Some(line_col(text, pos))
}

/// 1-based line and column (in characters) of a byte offset.
pub fn line_col(text: &str, pos: usize) -> (usize, usize) {
    let before = &text[..pos.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

fn skip_ws(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && matches!(b[i], b' ' | b'\t' | b'\n' | b'\r') {
        i += 1;
    }
    i
}

/// Returns the position just past the string that starts at `i` (which must be a quote), and the
/// string's raw contents (escapes left as written: keys in scene files are plain).
fn scan_string(b: &[u8], i: usize) -> Option<(usize, &[u8])> {
    if b.get(i) != Some(&b'"') {
        return None;
    }
    let mut j = i + 1;
    while j < b.len() {
        match b[j] {
            b'\\' => j += 2,
            b'"' => return Some((j + 1, &b[i + 1..j])),
            _ => j += 1,
        }
    }
    None
}

/// Position just past the value that starts at `i` (after whitespace).
fn skip_value(b: &[u8], i: usize) -> Option<usize> {
    let i = skip_ws(b, i);
    match *b.get(i)? {
        b'"' => scan_string(b, i).map(|(j, _)| j),
        b'{' | b'[' => {
            let mut depth = 0usize;
            let mut j = i;
            while j < b.len() {
                match b[j] {
                    b'"' => {
                        j = scan_string(b, j)?.0;
                        continue;
                    }
                    b'{' | b'[' => depth += 1,
                    b'}' | b']' => {
                        depth -= 1;
                        if depth == 0 {
                            return Some(j + 1);
                        }
                    }
                    _ => {}
                }
                j += 1;
            }
            None
        }
        _ => {
            let mut j = i;
            while j < b.len() && !matches!(b[j], b',' | b'}' | b']' | b' ' | b'\n' | b'\r' | b'\t')
            {
                j += 1;
            }
            Some(j)
        }
    }
}

fn find(b: &[u8], i: usize, path: &[Seg]) -> Option<usize> {
    let i = skip_ws(b, i);
    let Some(first) = path.first() else {
        return Some(i);
    };
    match (first, *b.get(i)?) {
        (Seg::Key(key), b'{') => {
            let mut j = skip_ws(b, i + 1);
            loop {
                if b.get(j) == Some(&b'}') {
                    return None;
                }
                let (after_key, k) = scan_string(b, j)?;
                j = skip_ws(b, after_key);
                if b.get(j) != Some(&b':') {
                    return None;
                }
                if k == key.as_bytes() {
                    return find(b, j + 1, &path[1..]);
                }
                j = skip_ws(b, skip_value(b, j + 1)?);
                match b.get(j) {
                    Some(b',') => j = skip_ws(b, j + 1),
                    _ => return None,
                }
            }
        }
        (Seg::Index(n), b'[') => {
            let mut j = skip_ws(b, i + 1);
            let mut k = 0;
            loop {
                if b.get(j) == Some(&b']') {
                    return None;
                }
                if k == *n {
                    return find(b, j, &path[1..]);
                }
                j = skip_ws(b, skip_value(b, j)?);
                match b.get(j) {
                    Some(b',') => j = skip_ws(b, j + 1),
                    _ => return None,
                }
                k += 1;
            }
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DOC: &str = "{\n  \"a\": [1, {\"b\": \"x,]\"}],\n  \"c\": {\"d\": [[0, 1], [2,\n 3]]}\n}";

    #[test]
    fn paths_print_like_rust_field_access() {
        let p = JsonPath::root()
            .key("triangles")
            .index(12)
            .key("v")
            .index(1);
        assert_eq!(p.to_string(), "triangles[12].v[1]");
    }

    #[test]
    fn locate_finds_nested_values() {
        let p = JsonPath::root().key("a").index(1).key("b");
        assert_eq!(locate(DOC, &p), Some((2, 18)));
        let p = JsonPath::root().key("c").key("d").index(1).index(1);
        assert_eq!(locate(DOC, &p), Some((4, 2)));
        let p = JsonPath::root().key("c").key("missing");
        assert_eq!(locate(DOC, &p), None);
    }
}
