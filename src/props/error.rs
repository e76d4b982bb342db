//! Scene-file errors and warnings that point at the source: `file:line:col: message`, followed by
//! the offending line and a caret under the column (the style of rustc and miette).

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A scene file's text, kept to locate errors.
#[derive(Debug)]
pub struct SourceFile {
    /// Path as given (relative paths stay relative, so messages do not name the user's home).
    pub path: PathBuf,
    /// The file's contents.
    pub text: String,
}

/// The most characters of a source line an error shows.
const SNIPPET_CHARS: usize = 100;

/// A byte offset in a scene file.
#[derive(Clone, Debug)]
pub struct Loc {
    /// The file.
    pub file: Arc<SourceFile>,
    /// Byte offset into its text.
    pub offset: usize,
}

impl Loc {
    /// 1-based line and column (in characters) of the offset.
    pub fn line_col(&self) -> (usize, usize) {
        let before = &self.file.text[..self.offset.min(self.file.text.len())];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        (line, before[line_start..].chars().count() + 1)
    }

    /// The scene file's folder, against which relative paths resolve.
    pub fn dir(&self) -> &Path {
        self.file.path.parent().unwrap_or(Path::new(""))
    }

    /// `file:line:col`.
    pub fn position(&self) -> String {
        let (line, col) = self.line_col();
        format!("{}:{line}:{col}", self.file.path.display())
    }

    /// The source line of the offset with a caret under its column; of a long line, the
    /// [`SNIPPET_CHARS`] characters around the column, elided with `…`.
    fn snippet(&self) -> String {
        let (line, col) = self.line_col();
        let text = self.file.text.lines().nth(line - 1).unwrap_or("");
        let gutter = line.to_string();
        let pad = " ".repeat(gutter.len());
        let chars: Vec<char> = text.chars().collect();
        let (start, end) = if chars.len() <= SNIPPET_CHARS {
            (0, chars.len())
        } else {
            let start = (col - 1).saturating_sub(SNIPPET_CHARS / 2).min(chars.len() - SNIPPET_CHARS);
            (start, start + SNIPPET_CHARS)
        };
        let before = if start > 0 { "…" } else { "" };
        let after = if end < chars.len() { "…" } else { "" };
        let shown: String = chars[start..end].iter().collect();
        let caret_pad: String = before
            .chars()
            .chain(chars[start..(col - 1).clamp(start, end)].iter().copied())
            .map(|c| if c == '\t' { '\t' } else { ' ' })
            .collect();
        format!("{pad} |\n{gutter} | {before}{shown}{after}\n{pad} | {caret_pad}^")
    }
}

/// An error in a scene: where (if known) and what was expected.
#[derive(Clone, Debug)]
pub struct SceneError {
    /// Where the problem is.
    pub loc: Option<Loc>,
    /// What is wrong and what was expected.
    pub message: String,
}

impl SceneError {
    /// An error at `loc`.
    pub fn at(loc: &Loc, message: impl Into<String>) -> SceneError {
        SceneError { loc: Some(loc.clone()), message: message.into() }
    }

    /// An error without a position (e.g. a file that cannot be read).
    pub fn new(message: impl Into<String>) -> SceneError {
        SceneError { loc: None, message: message.into() }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.loc {
            Some(loc) => write!(f, "{}: {}\n{}", loc.position(), self.message, loc.snippet()),
            None => write!(f, "{}", self.message),
        }
    }
}

impl std::error::Error for SceneError {}

pub use crate::choice::nearest;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_snippets_and_suggestions() {
        let file =
            Arc::new(SourceFile { path: "scene.xml".into(), text: "<scene>\n  <bsdf type=\"difuse\"/>\n".into() });
        let loc = Loc { file, offset: 10 };
        assert_eq!(loc.line_col(), (2, 3));
        let e = SceneError::at(&loc, "unknown BSDF").to_string();
        assert!(e.starts_with("scene.xml:2:3: unknown BSDF\n"), "{e}");
        assert!(e.contains("2 |   <bsdf type=\"difuse\"/>\n  |   ^"), "{e}");
        // A long line shows the part around the column.
        let long = format!("<scene>{}<bsdf type=\"x\"/>{}</scene>", " ".repeat(500), " ".repeat(500));
        let loc = Loc { file: Arc::new(SourceFile { path: "s.xml".into(), text: long }), offset: 507 };
        let e = SceneError::at(&loc, "here").to_string();
        let lines: Vec<&str> = e.lines().collect();
        assert!(lines[2].chars().count() < 120 && lines[2].contains("<bsdf type=\"x\"/>"), "{e}");
        let caret = lines[3].chars().position(|c| c == '^').unwrap();
        assert_eq!(lines[2].chars().nth(caret), Some('<'), "{e}");
        assert_eq!(nearest("difuse", ["diffuse", "dielectric", "conductor"]), Some("diffuse"));
        assert_eq!(nearest("roughplastik", ["plastic", "roughplastic"]), Some("roughplastic"));
        assert_eq!(nearest("xyzzy", ["diffuse", "plastic"]), None);
    }
}
