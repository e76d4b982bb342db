//! Where things are in a glTF file's JSON text, so that errors point at `file:line:col`: a
//! JSON path as the `gltf` crate's validator writes it (`meshes[0].primitives[1].attributes
//! ["POSITION"]`) resolved to the byte offset of that value; and the base64 of `data:` URIs.

/// One step of a JSON path.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Seg {
    /// An object member.
    Key(String),
    /// An array element.
    Index(usize),
}

/// Parses a path in the `gltf` crate's notation (`a.b[3]["key"]`, an optional ` = "value"`
/// suffix ignored) into segments.
pub fn parse_path(path: &str) -> Vec<Seg> {
    let path = path.split(" = ").next().unwrap_or("");
    let mut segs = Vec::new();
    let mut rest = path;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix('.') {
            rest = r;
        } else if let Some(r) = rest.strip_prefix("[\"") {
            let end = r.find("\"]").unwrap_or(r.len());
            segs.push(Seg::Key(r[..end].to_string()));
            rest = r.get(end + 2..).unwrap_or("");
        } else if let Some(r) = rest.strip_prefix('[') {
            let end = r.find(']').unwrap_or(r.len());
            match r[..end].parse() {
                Ok(i) => segs.push(Seg::Index(i)),
                Err(_) => break,
            }
            rest = r.get(end + 1..).unwrap_or("");
        } else {
            let end = rest.find(['.', '[']).unwrap_or(rest.len());
            segs.push(Seg::Key(rest[..end].to_string()));
            rest = &rest[end..];
        }
    }
    segs
}

/// The byte offset of the value at `path` in the JSON `text`, or of the deepest enclosing
/// value that exists (the document's start at worst).
pub fn locate(text: &str, path: &[Seg]) -> usize {
    let b = text.as_bytes();
    let mut pos = skip_ws(b, 0);
    for seg in path {
        match find_child(b, pos, seg) {
            Some(p) => pos = p,
            None => break,
        }
    }
    pos
}

/// The offsets of the elements of the document's top-level arrays (`nodes[3]`, `meshes[0]`, …),
/// found in one pass, so that locating a path inside an element does not rescan the file (a
/// `.gltf` with embedded buffers holds megabytes of base64 before its meshes).
#[derive(Debug, Default)]
pub struct Index {
    elements: std::collections::HashMap<String, Vec<usize>>,
}

impl Index {
    /// Indexes `text`.
    pub fn new(text: &str) -> Index {
        let b = text.as_bytes();
        let mut elements = std::collections::HashMap::new();
        let mut j = skip_ws(b, 0);
        if b.get(j) != Some(&b'{') {
            return Index { elements };
        }
        j = skip_ws(b, j + 1);
        while j < b.len() && b[j] == b'"' {
            let end = skip_string(b, j);
            let key = std::str::from_utf8(&b[j + 1..end.saturating_sub(1).max(j + 1)]).unwrap_or("").to_string();
            j = skip_ws(b, end);
            if b.get(j) != Some(&b':') {
                break;
            }
            j = skip_ws(b, j + 1);
            if b.get(j) == Some(&b'[') {
                let mut offsets = Vec::new();
                let mut k = skip_ws(b, j + 1);
                while k < b.len() && b[k] != b']' {
                    offsets.push(k);
                    k = skip_ws(b, skip_value(b, k));
                    if b.get(k) == Some(&b',') {
                        k = skip_ws(b, k + 1);
                    } else {
                        break;
                    }
                }
                elements.insert(key, offsets);
            }
            j = skip_ws(b, skip_value(b, j));
            if b.get(j) == Some(&b',') {
                j = skip_ws(b, j + 1);
            }
        }
        Index { elements }
    }

    /// [`locate`], starting from the indexed element when the path begins with one.
    pub fn locate(&self, text: &str, path: &[Seg]) -> usize {
        if let [Seg::Key(k), Seg::Index(i), rest @ ..] = path {
            if let Some(&start) = self.elements.get(k).and_then(|v| v.get(*i)) {
                let b = text.as_bytes();
                let mut pos = start;
                for seg in rest {
                    match find_child(b, pos, seg) {
                        Some(p) => pos = p,
                        None => break,
                    }
                }
                return pos;
            }
        }
        locate(text, path)
    }
}

fn skip_ws(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && b[i].is_ascii_whitespace() {
        i += 1;
    }
    i
}

/// The end of the string starting at `i` (which holds `"`), past its closing quote.
fn skip_string(b: &[u8], mut i: usize) -> usize {
    i += 1;
    while i < b.len() {
        match b[i] {
            b'\\' => i += 2,
            b'"' => return i + 1,
            _ => i += 1,
        }
    }
    b.len()
}

/// The end of the value starting at `i`.
fn skip_value(b: &[u8], i: usize) -> usize {
    match b.get(i) {
        Some(b'"') => skip_string(b, i),
        Some(b'{' | b'[') => {
            let mut depth = 0usize;
            let mut j = i;
            while j < b.len() {
                match b[j] {
                    b'"' => {
                        j = skip_string(b, j);
                        continue;
                    }
                    b'{' | b'[' => depth += 1,
                    b'}' | b']' => {
                        depth -= 1;
                        if depth == 0 {
                            return j + 1;
                        }
                    }
                    _ => {}
                }
                j += 1;
            }
            b.len()
        }
        _ => {
            let mut j = i;
            while j < b.len() && !matches!(b[j], b',' | b'}' | b']') && !b[j].is_ascii_whitespace() {
                j += 1;
            }
            j
        }
    }
}

/// The offset of the member or element `seg` of the container value at `i`.
fn find_child(b: &[u8], i: usize, seg: &Seg) -> Option<usize> {
    match (b.get(i)?, seg) {
        (b'{', Seg::Key(key)) => {
            let mut j = skip_ws(b, i + 1);
            while j < b.len() && b[j] == b'"' {
                let end = skip_string(b, j);
                let name = std::str::from_utf8(&b[j + 1..end.saturating_sub(1).max(j + 1)]).ok()?;
                j = skip_ws(b, end);
                if b.get(j) != Some(&b':') {
                    return None;
                }
                j = skip_ws(b, j + 1);
                if name == key {
                    return Some(j);
                }
                j = skip_ws(b, skip_value(b, j));
                if b.get(j) == Some(&b',') {
                    j = skip_ws(b, j + 1);
                }
            }
            None
        }
        (b'[', Seg::Index(n)) => {
            let mut j = skip_ws(b, i + 1);
            let mut k = 0;
            while j < b.len() && b[j] != b']' {
                if k == *n {
                    return Some(j);
                }
                j = skip_ws(b, skip_value(b, j));
                if b.get(j) == Some(&b',') {
                    j = skip_ws(b, j + 1);
                }
                k += 1;
            }
            None
        }
        _ => None,
    }
}

/// Decodes standard base64 (RFC 4648, `=` padding optional; whitespace skipped).
pub fn base64_decode(text: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(text.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0u32);
    for (i, c) in text.bytes().enumerate() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => break,
            c if c.is_ascii_whitespace() => continue,
            _ => return Err(format!("invalid base64 character {:?} at position {i}", c as char)),
        };
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Ok(out)
}

/// Decodes `%XX` escapes of a URI (glTF's relative file URIs).
pub fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Some(v) = uri.get(i + 1..i + 3).and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_resolve_to_their_values() {
        let text = "{\n  \"asset\": {\"version\": \"2.0\"},\n  \"meshes\": [\n    {\"name\": \"a\"},\n    {\"primitives\": [{\"attributes\": {\"NORMAL\": 1, \"POSITION\": 7}}]}\n  ]\n}";
        let path = parse_path("meshes[1].primitives[0].attributes[\"POSITION\"] = \"x\"");
        assert_eq!(
            path,
            vec![
                Seg::Key("meshes".into()),
                Seg::Index(1),
                Seg::Key("primitives".into()),
                Seg::Index(0),
                Seg::Key("attributes".into()),
                Seg::Key("POSITION".into())
            ]
        );
        let at = locate(text, &path);
        assert_eq!(&text[at..at + 1], "7");
        // A missing member stops at the deepest value that exists.
        let at = locate(text, &parse_path("meshes[0].primitives"));
        assert!(text[at..].starts_with("{\"name\""), "{}", &text[at..]);
        assert_eq!(locate(text, &parse_path("nodes[3]")), 0);
        // The index finds the same places.
        let index = Index::new(text);
        for p in [
            "meshes[1].primitives[0].attributes[\"POSITION\"]",
            "meshes[0].primitives",
            "asset.version",
            "nodes[3]",
            "meshes[7]",
        ] {
            assert_eq!(index.locate(text, &parse_path(p)), locate(text, &parse_path(p)), "{p}");
        }
        // Strings with escaped quotes and brackets are skipped whole.
        let t = r#"{"a": "x\"]}", "b": [1, [2, 3], {"c": "]"}, 4]}"#;
        let at = locate(t, &parse_path("b[3]"));
        assert_eq!(&t[at..at + 1], "4");
    }

    #[test]
    fn base64_and_percent_decoding() {
        assert_eq!(base64_decode("aGVsbG8gd29ybGQ=").unwrap(), b"hello world");
        assert_eq!(base64_decode("AAECAw").unwrap(), [0, 1, 2, 3]);
        assert!(base64_decode("ab*c").is_err());
        assert_eq!(percent_decode("my%20file.bin"), "my file.bin");
        assert_eq!(percent_decode("100%"), "100%");
    }
}
