//! Where relative file names in a scene are looked for: Mitsuba's file resolver. A list of
//! search folders, most recently added first; a relative name resolves to the first folder that
//! holds it, or stays as written (relative to the working directory) when none does, so that
//! the error names the file as the scene wrote it.
//!
//! For a Mitsuba scene the list starts as the main scene file's folder, then the working
//! directory; each `<path value="…"/>` puts a folder in front. Included files and every file a
//! plugin names (meshes, images, spectra) resolve through the same list — not against the folder
//! of the file that names them.

use std::path::{Path, PathBuf};

/// Search folders for relative file names (see the module docs).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FileResolver {
    /// Most recently added first; an empty path is the working directory.
    folders: Vec<PathBuf>,
}

impl FileResolver {
    /// The resolver of a scene file: its folder, then the working directory.
    pub fn for_scene(scene: &Path) -> FileResolver {
        let dir = scene.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut folders = vec![dir];
        if folders[0] != Path::new("") {
            folders.push(PathBuf::new());
        }
        FileResolver { folders }
    }

    /// Puts `folder` in front of the search list (Mitsuba's `prepend`); an existing entry moves
    /// to the front.
    pub fn prepend(&mut self, folder: PathBuf) {
        self.folders.retain(|f| *f != folder);
        self.folders.insert(0, folder);
    }

    /// The search folders, first searched first.
    pub fn folders(&self) -> &[PathBuf] {
        &self.folders
    }

    /// The file `name` names: itself if absolute, else the first search folder that holds it,
    /// else `name` as written.
    pub fn resolve(&self, name: &str) -> PathBuf {
        let p = Path::new(name);
        if p.is_absolute() {
            return p.to_path_buf();
        }
        self.folders.iter().map(|f| f.join(p)).find(|c| c.exists()).unwrap_or_else(|| p.to_path_buf())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_folder_that_holds_the_file_wins() {
        let dir = std::env::temp_dir().join(format!("neumann-resolver-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("a")).unwrap();
        std::fs::create_dir_all(dir.join("b")).unwrap();
        std::fs::write(dir.join("a/x.txt"), "a").unwrap();
        std::fs::write(dir.join("b/x.txt"), "b").unwrap();
        std::fs::write(dir.join("b/y.txt"), "b").unwrap();
        let mut r = FileResolver::for_scene(&dir.join("scene.xml"));
        assert_eq!(r.folders(), [dir.clone(), PathBuf::new()]);
        assert_eq!(r.resolve("a/x.txt"), dir.join("a/x.txt"));
        r.prepend(dir.join("b"));
        r.prepend(dir.join("a"));
        assert_eq!(r.resolve("x.txt"), dir.join("a/x.txt"), "the most recent folder first");
        assert_eq!(r.resolve("y.txt"), dir.join("b/y.txt"));
        assert_eq!(r.resolve("missing.txt"), PathBuf::from("missing.txt"), "unresolved names stay as written");
        assert_eq!(r.resolve("/abs/z.txt"), PathBuf::from("/abs/z.txt"));
        r.prepend(dir.join("b"));
        assert_eq!(r.folders()[0], dir.join("b"));
        assert_eq!(r.folders().len(), 4, "no duplicates");
        std::fs::remove_dir_all(&dir).ok();
    }
}
