//! The standard library (`stdlib/`: the course library, `radiosity.inc`) built into the binary,
//! so that an `occ` installed anywhere (`cargo install --path cli`) finds it with no folder
//! beside it. Files on disk come first (see [`crate::frontend`]); these answer when none is.

/// Every file of `stdlib/`, by name.
pub const FILES: &[(&str, &str)] = &[
    (
        "course-file.inc",
        include_str!("../../stdlib/course-file.inc"),
    ),
    (
        "course-nets.inc",
        include_str!("../../stdlib/course-nets.inc"),
    ),
    (
        "course-random.inc",
        include_str!("../../stdlib/course-random.inc"),
    ),
    (
        "course-real.inc",
        include_str!("../../stdlib/course-real.inc"),
    ),
    (
        "course-screen.inc",
        include_str!("../../stdlib/course-screen.inc"),
    ),
    (
        "course-strings.inc",
        include_str!("../../stdlib/course-strings.inc"),
    ),
    ("course.inc", include_str!("../../stdlib/course.inc")),
    ("course.lib", include_str!("../../stdlib/course.lib")),
    ("course.module", include_str!("../../stdlib/course.module")),
    ("radiosity.inc", include_str!("../../stdlib/radiosity.inc")),
];

/// The path an embedded file is known by in diagnostics.
pub const PREFIX: &str = "<occ stdlib>";

/// The text of embedded file `name`.
pub fn get(name: &str) -> Option<&'static str> {
    FILES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, text)| *text)
}

#[cfg(test)]
mod tests {
    /// The list is the folder: every file of `stdlib/` is embedded with its contents.
    #[test]
    fn every_stdlib_file_is_embedded() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../stdlib");
        let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
            .expect("stdlib folder")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        on_disk.sort();
        let embedded: Vec<&str> = super::FILES.iter().map(|(n, _)| *n).collect();
        assert_eq!(on_disk, embedded);
        for (name, text) in super::FILES {
            let disk = std::fs::read_to_string(dir.join(name)).expect("stdlib file");
            assert_eq!(disk, *text, "{name}");
        }
    }
}
