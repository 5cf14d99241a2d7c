//! Finding test files: every `*.occ` file under the given paths, in a stable order.
//!
//! Folders are walked recursively; nothing is listed by hand. Files named on the command line are
//! taken whatever their extension. Helper files that tests `#INCLUDE` should use another extension
//! (`.inc`) so that they are not mistaken for tests.

use std::fmt;
use std::fs;
use std::path::{Path, PathBuf};

/// Why the test files could not be listed.
#[derive(Debug)]
pub enum DiscoverError {
    /// Occurs when a path given on the command line does not exist.
    Missing(PathBuf),
    /// Occurs when a folder cannot be read.
    Unreadable(PathBuf, std::io::Error),
}

impl fmt::Display for DiscoverError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DiscoverError::Missing(path) => write!(f, "{}: no such file or folder", path.display()),
            DiscoverError::Unreadable(path, error) => {
                write!(f, "{}: cannot read folder: {error}", path.display())
            }
        }
    }
}

impl std::error::Error for DiscoverError {}

/// Lists the test files under `paths`, sorted and without duplicates.
pub fn test_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, DiscoverError> {
    let mut files = Vec::new();
    for path in paths {
        if path.is_dir() {
            walk(path, &mut files)?;
        } else if path.is_file() {
            files.push(path.clone());
        } else {
            return Err(DiscoverError::Missing(path.clone()));
        }
    }
    files.sort();
    files.dedup();
    Ok(files)
}

/// Adds every `.occ` file under `folder`.
fn walk(folder: &Path, files: &mut Vec<PathBuf>) -> Result<(), DiscoverError> {
    let entries =
        fs::read_dir(folder).map_err(|e| DiscoverError::Unreadable(folder.to_path_buf(), e))?;
    for entry in entries {
        let path = entry
            .map_err(|e| DiscoverError::Unreadable(folder.to_path_buf(), e))?
            .path();
        if path.is_dir() {
            walk(&path, files)?;
        } else if path.extension().is_some_and(|ext| ext == "occ") {
            files.push(path);
        }
    }
    Ok(())
}
