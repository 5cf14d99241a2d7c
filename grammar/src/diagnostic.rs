//! Diagnostics of the front end, in one shape for every stage, renderable with miette.

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

/// Where a diagnostic points.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Place {
    /// A span of the preprocessed text (lexer and parser).
    Output(Span),
    /// A range of an original file (preprocessor).
    File(Location),
}

/// One diagnostic: message, label at a place, optional help.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Diagnostic {
    /// Error or warning.
    pub severity: Severity,
    /// The one-line message.
    pub message: String,
    /// The label drawn under the place ("I was expecting ... here").
    pub label: String,
    /// Advice in occam terms, when the fix is clear.
    pub help: Option<String>,
    /// Where.
    pub place: Place,
}

impl Diagnostic {
    /// Creates an error at a span of the preprocessed text.
    pub fn error(span: Span, message: impl Into<String>, label: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Error,
            message: message.into(),
            label: label.into(),
            help: None,
            place: Place::Output(span),
        }
    }

    /// Adds help text.
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    /// Turns the diagnostic into a warning.
    pub fn warning(mut self) -> Self {
        self.severity = Severity::Warning;
        self
    }

    /// Resolves the place to an original file location (`None` only for an empty map).
    pub fn locate(&self, map: &SourceMap) -> Option<Location> {
        match &self.place {
            Place::Output(span) => map.locate(*span),
            Place::File(location) => Some(location.clone()),
        }
    }

    /// Builds a miette report showing the original file's text.
    pub fn to_report(&self, map: &SourceMap) -> miette::Report {
        let severity = match self.severity {
            Severity::Error => miette::Severity::Error,
            Severity::Warning => miette::Severity::Warning,
        };
        let mut diag = miette::MietteDiagnostic::new(self.message.clone()).with_severity(severity);
        if let Some(help) = &self.help {
            diag = diag.with_help(help.clone());
        }
        let Some(location) = self.locate(map) else {
            return miette::Report::new(diag);
        };
        let label = miette::LabeledSpan::at(location.range.clone(), self.label.clone());
        diag = diag.with_label(label);
        match map.files.get(location.file) {
            Some(file) => miette::Report::new(diag).with_source_code(miette::NamedSource::new(
                file.path.clone(),
                file.shared_text(),
            )),
            None => miette::Report::new(diag),
        }
    }
}
