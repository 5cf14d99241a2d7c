//! The front end as one IO-free call: preprocess, parse and check a program whose files come
//! through a [`Loader`]. The code generator's `front_end` adds the binding of `#PRAGMA EXTERNAL`
//! routines on top; `occ check`, `occ run`, the tests, the benchmarks and the fuzz target all go
//! through one of the two.

use occ_grammar::Parsed;
use occ_grammar::diagnostic::Diagnostic;
use occ_grammar::preprocess::Loader;

use crate::{CheckedProgram, Options};

/// A program through the front end: its parse, the checker's tables when there are no errors,
/// and every diagnostic (errors and warnings, of every pass, in the order the passes found them).
#[derive(Debug)]
pub struct Front {
    /// The preprocessed, parsed program (partial when there are syntax errors).
    pub parsed: Parsed,
    /// The checker's side tables for `parsed.program`; `None` when any diagnostic is an error.
    pub checked: Option<CheckedProgram>,
    /// Every diagnostic; spans are offsets into `parsed.text`, located through `parsed.map`.
    pub diagnostics: Vec<Diagnostic>,
}

impl Front {
    /// Reports whether any diagnostic is an error.
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }
}

/// Preprocesses, parses and checks the file `path` whose text is `text`, with the checks its
/// `#OPTION` directives switch off switched off. Never panics, whatever the input.
///
/// The checker runs only on a complete tree: on a partial one every dropped declaration would
/// come back as a cascade of "not declared" errors. A complete tree may still carry syntax
/// errors that drop nothing (operators mixed without parentheses), so those and the checker's
/// errors are reported in one run.
pub fn check_source(path: &str, text: &str, loader: &mut dyn Loader) -> Front {
    let parsed = occ_grammar::parse_source(path, text, loader);
    let mut diagnostics = parsed.diagnostics.clone();
    let mut checked = None;
    if parsed.complete {
        let options = Options::from_letters(&parsed.options);
        let (program, found) = crate::check_with(&parsed.program, options);
        diagnostics.extend(found.iter().map(crate::Diagnostic::to_diagnostic));
        checked = program;
    }
    if diagnostics.iter().any(Diagnostic::is_error) {
        checked = None;
    }
    Front {
        parsed,
        checked,
        diagnostics,
    }
}

#[cfg(test)]
mod test {
    use std::collections::HashMap;

    /// A PAR usage error, and `#INCLUDE "opts.inc"` before it.
    const RACE: &str =
        "#INCLUDE \"opts.inc\"\nPROC p ()\n  INT x, y:\n  PAR\n    x := 1\n    y := x\n:\n";

    fn errors(opts: &str) -> usize {
        let mut files: HashMap<String, String> = HashMap::new();
        files.insert("opts.inc".into(), opts.into());
        let front = super::check_source("t.occ", RACE, &mut files);
        assert_eq!(front.checked.is_some(), !front.has_errors());
        front.diagnostics.iter().filter(|d| d.is_error()).count()
    }

    #[test]
    fn usage_checks_apply_by_default() {
        assert_eq!(errors("-- nothing\n"), 1);
    }

    #[test]
    fn an_option_in_an_included_file_switches_usage_checks_off() {
        assert_eq!(errors("#OPTION \"N\"\n"), 0);
    }

    #[test]
    fn an_option_inside_a_false_if_does_nothing() {
        assert_eq!(errors("#IF FALSE\n#OPTION \"N\"\n#ENDIF\n"), 1);
    }
}
