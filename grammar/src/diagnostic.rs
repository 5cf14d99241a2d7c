//! The one diagnostic type of occ, produced by every pass (preprocessor, lexer, parser, checker,
//! EXTERNAL binding, code generator), and its one renderer ([`Diagnostic::to_report`]), used by
//! `occ check`, `occ run`, `occ test` and the snapshot tests alike.
//!
//! A diagnostic has a message, a severity, a primary label at a place, any number of related
//! labels at other places, optional help and an optional code naming what went wrong (the
//! checker's `DiagnosticKind` variant, for example). Places are spans of the preprocessed text
//! or ranges of an original file; a [`SourceMap`] maps both back to files and lines.

use crate::ast::Span;
use crate::source_map::{Location, SourceMap};

/// How serious a diagnostic is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Severity {
    /// The program is rejected.
    Error,
    /// The program is accepted, but something deserves attention.
    Warning,
}

/// Where a label points.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Place {
    /// A span of the preprocessed text (lexer, parser, checker, code generator).
    Output(Span),
    /// A range of an original file (preprocessor).
    File(Location),
    /// No one place: the problem is the program's as a whole ("no top-level PROC").
    Program,
}

/// A secondary label: text drawn under another place ("written in another branch").
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Label {
    /// Where.
    pub place: Place,
    /// What is there.
    pub text: String,
}

/// One diagnostic: message, primary label at a place, related labels, optional help and code.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Diagnostic {
    /// Error or warning.
    pub severity: Severity,
    /// The one-line message.
    pub message: String,
    /// The label drawn under the place ("I was expecting ... here").
    pub label: String,
    /// Where.
    pub place: Place,
    /// Further labels at related places, drawn with the primary one.
    pub related: Vec<Label>,
    /// Advice in occam terms, when the fix is clear.
    pub help: Option<String>,
    /// A stable name for what went wrong (`check::ParUsage`), for tools and tests.
    pub code: Option<String>,
}

impl Diagnostic {
    /// Creates an error at a span of the preprocessed text.
    pub fn error(span: Span, message: impl Into<String>, label: impl Into<String>) -> Self {
        Self::at(Place::Output(span), message, label)
    }

    /// Creates an error at any place.
    pub fn at(place: Place, message: impl Into<String>, label: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Error,
            message: message.into(),
            label: label.into(),
            place,
            related: Vec::new(),
            help: None,
            code: None,
        }
    }

    /// Creates an error about the program as a whole, with no place to point at.
    pub fn program(message: impl Into<String>) -> Self {
        Self::at(Place::Program, message, "")
    }

    /// Adds help text.
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    /// Adds a related label at a span of the preprocessed text.
    pub fn with_related(mut self, span: Span, text: impl Into<String>) -> Self {
        self.related.push(Label {
            place: Place::Output(span),
            text: text.into(),
        });
        self
    }

    /// Sets the code.
    pub fn with_code(mut self, code: impl Into<String>) -> Self {
        self.code = Some(code.into());
        self
    }

    /// Turns the diagnostic into a warning.
    pub fn warning(mut self) -> Self {
        self.severity = Severity::Warning;
        self
    }

    /// Reports whether this is an error.
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }

    /// The span of the primary place in the preprocessed text, if it has one.
    pub fn span(&self) -> Option<Span> {
        match &self.place {
            Place::Output(span) => Some(*span),
            Place::File(_) | Place::Program => None,
        }
    }

    /// Resolves the primary place to an original file location (`None` for a diagnostic about
    /// the whole program, or an empty map).
    pub fn locate(&self, map: &SourceMap) -> Option<Location> {
        locate(&self.place, map)
    }

    /// The path of the file the primary place is in and its 1-based line (`None` as
    /// [`Diagnostic::locate`]).
    pub fn file_line<'m>(&self, map: &'m SourceMap) -> Option<(&'m str, usize)> {
        let location = self.locate(map)?;
        Some((map.files.get(location.file)?.path.as_str(), location.line))
    }

    /// Builds the miette report users see: the primary file's text with every label in it, and
    /// a `file:line: label` note for a related label in another file.
    pub fn to_report(&self, map: &SourceMap) -> miette::Report {
        let severity = match self.severity {
            Severity::Error => miette::Severity::Error,
            Severity::Warning => miette::Severity::Warning,
        };
        let mut diag = miette::MietteDiagnostic::new(self.message.clone()).with_severity(severity);
        if let Some(code) = &self.code {
            diag = diag.with_code(code.clone());
        }
        let primary = self.locate(map);
        let file = primary.as_ref().map(|l| l.file);
        let mut labels = Vec::new();
        let mut notes = Vec::new();
        if let Some(location) = &primary {
            labels.push(miette::LabeledSpan::new_primary_with_span(
                Some(self.label.clone()),
                location.range.clone(),
            ));
        }
        for label in &self.related {
            match locate(&label.place, map) {
                Some(l) if Some(l.file) == file => labels.push(miette::LabeledSpan::new_with_span(
                    Some(label.text.clone()),
                    l.range,
                )),
                Some(l) => {
                    let path = map.files.get(l.file).map_or("?", |f| f.path.as_str());
                    notes.push(format!("{path}:{}: {}", l.line, label.text));
                }
                None => notes.push(label.text.clone()),
            }
        }
        let help = self.help.iter().cloned().chain(notes).collect::<Vec<_>>();
        if !help.is_empty() {
            diag = diag.with_help(help.join("\n"));
        }
        diag = diag.with_labels(labels);
        match file.and_then(|f| map.files.get(f)) {
            Some(file) => miette::Report::new(diag).with_source_code(miette::NamedSource::new(
                file.path.clone(),
                file.shared_text(),
            )),
            None => miette::Report::new(diag),
        }
    }
}

fn locate(place: &Place, map: &SourceMap) -> Option<Location> {
    match place {
        Place::Output(span) => map.locate(*span),
        Place::File(location) => Some(location.clone()),
        Place::Program => None,
    }
}

impl std::fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}
