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
/// A leading UTF-8 byte order mark is skipped (the loader accepts one), so positions are those
/// an editor shows.
pub fn locate(text: &str, path: &JsonPath) -> Option<(usize, usize)> {
    let text = strip_bom(text);
    let bytes = text.as_bytes();
    let pos = find(bytes, 0, &path.0)?;
    Some(line_col(text, pos))
}

/// The byte offset where the value at `path` begins in `text` (no byte order mark).
pub fn find_offset(text: &str, path: &JsonPath) -> Option<usize> {
    find(text.as_bytes(), 0, &path.0)
}

/// Where the value at `path` begins or, when it is not in the text (a defaulted field), where
/// its nearest enclosing value that is begins: every error then has a line and column.
pub fn locate_nearest(text: &str, path: &JsonPath) -> Option<(usize, usize)> {
    (0..=path.0.len())
        .rev()
        .find_map(|n| locate(text, &JsonPath(path.0[..n].to_vec())))
}

/// The text without a leading UTF-8 byte order mark.
pub fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// The byte offset of serde_json's (line, column), where the column counts bytes from 1 and 0
/// means "just after the line break" (taken as column 1). Clamped to the text and moved back to
/// a character boundary.
pub fn offset_of(text: &str, line: usize, column: usize) -> usize {
    let mut start = 0;
    for _ in 1..line {
        match text[start..].find('\n') {
            Some(i) => start += i + 1,
            None => break,
        }
    }
    let mut pos = (start + column.max(1) - 1).min(text.len());
    while !text.is_char_boundary(pos) {
        pos -= 1;
    }
    pos
}

/// A key that appears twice in one JSON object: where the second one begins, the path of its
/// value, and where the first one begins (byte offsets).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DuplicateKey {
    pub at: usize,
    pub path: JsonPath,
    pub first_at: usize,
}

/// The first duplicate key in the document, comparing keys as decoded (`"a"` and `"\u0061"`
/// are the same key). serde keeps the last of duplicate map keys without a word, so the loader
/// looks for them first. Text that is not valid JSON (or nests deeper than serde_json's limit
/// of 128) ends the search with None: serde reports the syntax error.
pub fn duplicate_key(text: &str) -> Option<DuplicateKey> {
    let b = text.as_bytes();
    let mut path = Vec::new();
    match scan_dups(b, skip_ws(b, 0), &mut path, 0) {
        Err(Stop::Duplicate(d)) => Some(d),
        _ => None,
    }
}

enum Stop {
    Duplicate(DuplicateKey),
    Invalid,
}

/// The key's text as decoded: escapes resolved (raw bytes when they do not decode).
fn decode_key(quoted: &[u8]) -> String {
    let raw = &quoted[1..quoted.len() - 1];
    if raw.contains(&b'\\') {
        if let Ok(k) = serde_json::from_slice::<String>(quoted) {
            return k;
        }
    }
    String::from_utf8_lossy(raw).into_owned()
}

/// Scans the value at `i` (no leading whitespace); returns the position just past it.
fn scan_dups(b: &[u8], i: usize, path: &mut Vec<Seg>, depth: usize) -> Result<usize, Stop> {
    if depth > 128 {
        return Err(Stop::Invalid);
    }
    match b.get(i) {
        Some(b'{') => {
            let mut seen: std::collections::HashMap<String, usize> = Default::default();
            let mut j = skip_ws(b, i + 1);
            if b.get(j) == Some(&b'}') {
                return Ok(j + 1);
            }
            loop {
                let (after_key, _) = scan_string(b, j).ok_or(Stop::Invalid)?;
                let key = decode_key(&b[j..after_key]);
                if let Some(&first_at) = seen.get(&key) {
                    path.push(Seg::Key(key));
                    return Err(Stop::Duplicate(DuplicateKey {
                        at: j,
                        path: JsonPath(path.clone()),
                        first_at,
                    }));
                }
                seen.insert(key.clone(), j);
                let colon = skip_ws(b, after_key);
                if b.get(colon) != Some(&b':') {
                    return Err(Stop::Invalid);
                }
                path.push(Seg::Key(key));
                let end = scan_dups(b, skip_ws(b, colon + 1), path, depth + 1)?;
                path.pop();
                j = skip_ws(b, end);
                match b.get(j) {
                    Some(b',') => j = skip_ws(b, j + 1),
                    Some(b'}') => return Ok(j + 1),
                    _ => return Err(Stop::Invalid),
                }
            }
        }
        Some(b'[') => {
            let mut j = skip_ws(b, i + 1);
            if b.get(j) == Some(&b']') {
                return Ok(j + 1);
            }
            let mut n = 0;
            loop {
                path.push(Seg::Index(n));
                let end = scan_dups(b, j, path, depth + 1)?;
                path.pop();
                j = skip_ws(b, end);
                match b.get(j) {
                    Some(b',') => j = skip_ws(b, j + 1),
                    Some(b']') => return Ok(j + 1),
                    _ => return Err(Stop::Invalid),
                }
                n += 1;
            }
        }
        Some(b'"') => scan_string(b, i).map(|(j, _)| j).ok_or(Stop::Invalid),
        Some(_) => match skip_value(b, i) {
            Some(j) if j > i => Ok(j),
            _ => Err(Stop::Invalid),
        },
        None => Err(Stop::Invalid),
    }
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
/// string's raw contents (escapes left as written; see [`decode_key`]).
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
                let matches = if k.contains(&b'\\') {
                    decode_key(&b[j..after_key]) == *key
                } else {
                    k == key.as_bytes()
                };
                j = skip_ws(b, after_key);
                if b.get(j) != Some(&b':') {
                    return None;
                }
                if matches {
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
