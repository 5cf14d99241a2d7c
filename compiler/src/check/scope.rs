//! Nested scopes: occam names scope from their declaration to the end of the process (or
//! construct) the declaration precedes, and an inner declaration hides an outer one.

use crate::checked::SymbolId;

/// The names in scope, innermost last.
#[derive(Debug, Default)]
pub struct Scope {
    names: crate::fxhash::FxHashMap<String, Vec<SymbolId>>,
    declared: Vec<String>,
    marks: Vec<usize>,
}

impl Scope {
    /// Opens a scope; [`Scope::close`] undoes every declaration made since.
    pub fn open(&mut self) {
        self.marks.push(self.declared.len());
    }

    /// Closes the innermost scope.
    pub fn close(&mut self) {
        let mark = self.marks.pop().unwrap_or(0);
        for name in self.declared.drain(mark..) {
            if let Some(stack) = self.names.get_mut(&name) {
                stack.pop();
            }
        }
    }

    /// Declares `name` in the innermost scope.
    pub fn declare(&mut self, name: &str, id: SymbolId) {
        self.names.entry(name.to_string()).or_default().push(id);
        self.declared.push(name.to_string());
    }

    /// Looks up the innermost visible declaration of `name`.
    pub fn lookup(&self, name: &str) -> Option<SymbolId> {
        self.names.get(name).and_then(|s| s.last().copied())
    }

    /// Iterates over every visible declaration of `name`, innermost first (for operators,
    /// which overload one another).
    pub fn lookup_all(&self, name: &str) -> impl Iterator<Item = SymbolId> + '_ {
        self.names
            .get(name)
            .into_iter()
            .flat_map(|s| s.iter().rev().copied())
    }
}
