//! pbrt-v4's tokens: identifiers (directives, `true`/`false`), quoted strings, numbers, `[` and
//! `]`; `#` starts a comment to the end of the line. Each token keeps its byte offset.

/// A token and where it starts.
#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    /// What it is.
    pub kind: Kind,
    /// Byte offset in the file's text.
    pub offset: usize,
}

/// Token kinds.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    /// A bare word: a directive or `true` / `false`.
    Ident(String),
    /// A quoted string (escapes `\"`, `\\`, `\n`, `\t` resolved).
    Str(String),
    /// A number.
    Num(f64),
    /// `[`.
    Open,
    /// `]`.
    Close,
}

impl Kind {
    /// How the token is named in messages.
    pub fn describe(&self) -> String {
        match self {
            Kind::Ident(s) => format!("'{s}'"),
            Kind::Str(s) => format!("\"{s}\""),
            Kind::Num(n) => format!("the number {n}"),
            Kind::Open => "'['".into(),
            Kind::Close => "']'".into(),
        }
    }
}

/// Splits `text` into tokens; an error is `(offset, message)`.
pub fn tokenize(text: &str) -> Result<Vec<Token>, (usize, String)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        match c {
            b' ' | b'\t' | b'\r' | b'\n' => i += 1,
            b'#' => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'[' => {
                out.push(Token { kind: Kind::Open, offset: i });
                i += 1;
            }
            b']' => {
                out.push(Token { kind: Kind::Close, offset: i });
                i += 1;
            }
            b'"' => {
                let start = i;
                i += 1;
                let mut s = Vec::new();
                loop {
                    match b.get(i) {
                        None | Some(b'\n') => return Err((start, "unterminated string (a '\"' is missing)".into())),
                        Some(b'"') => {
                            i += 1;
                            break;
                        }
                        Some(b'\\') => {
                            let e = *b.get(i + 1).ok_or((start, "unterminated string".to_string()))?;
                            s.push(match e {
                                b'n' => b'\n',
                                b't' => b'\t',
                                b'b' => 8,
                                b'f' => 12,
                                b'r' => b'\r',
                                other => other,
                            });
                            i += 2;
                        }
                        Some(&c) => {
                            s.push(c);
                            i += 1;
                        }
                    }
                }
                out.push(Token { kind: Kind::Str(String::from_utf8_lossy(&s).into_owned()), offset: start });
            }
            b'0'..=b'9' | b'-' | b'+' | b'.' => {
                let start = i;
                while i < b.len() && matches!(b[i], b'0'..=b'9' | b'-' | b'+' | b'.' | b'e' | b'E') {
                    i += 1;
                }
                let s = &text[start..i];
                let v: f64 = s.parse().map_err(|_| (start, format!("'{s}' is not a number")))?;
                out.push(Token { kind: Kind::Num(v), offset: start });
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                let start = i;
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
                out.push(Token { kind: Kind::Ident(text[start..i].to_string()), offset: start });
            }
            _ => {
                let ch = text[i..].chars().next().unwrap_or('?');
                return Err((i, format!("unexpected character '{ch}'")));
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_with_offsets() {
        let t = tokenize("Shape \"sphere\" # comment [\n \"float radius\" [ 2.5e0 ] -1 true").unwrap();
        let kinds: Vec<Kind> = t.iter().map(|t| t.kind.clone()).collect();
        assert_eq!(
            kinds,
            vec![
                Kind::Ident("Shape".into()),
                Kind::Str("sphere".into()),
                Kind::Str("float radius".into()),
                Kind::Open,
                Kind::Num(2.5),
                Kind::Close,
                Kind::Num(-1.0),
                Kind::Ident("true".into())
            ]
        );
        assert_eq!(t[2].offset, 28);
        assert_eq!(tokenize("\"open").unwrap_err().0, 0);
        assert!(tokenize("1.2.3").unwrap_err().1.contains("not a number"));
        assert!(tokenize("Shape @").unwrap_err().1.contains("unexpected character '@'"));
    }
}
