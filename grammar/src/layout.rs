//! occam's layout rule: turns physical lines into `NewLine`, `Indent` and `Dedent` tokens.
//!
//! Contract:
//! - Blank and comment-only lines are ignored.
//! - A line ending in an operator, `,`, `;`, `:=`, `IS`, `FROM`, `FOR`, `AFTER`, `RETYPES`, ...
//!   continues on the next line, which may be indented arbitrarily.
//! - Indentation grows in steps of two spaces; a line indented deeper than that, or back to a
//!   column that no enclosing line used, is reported (the token stream stays balanced, so the
//!   parser still sees every line).
//! - Names written before `FUNCTION` on the same line become `TypeName`s (result types).
//! - The indented lines under `ASM` / `GUY` become one opaque `AsmBody` token.
//! - At the end, every open indentation is closed, so `Indent`s and `Dedent`s always balance.

use crate::ast::Span;
use crate::diagnostic::Diagnostic;
use crate::lexer::{Kw, LexError, Token, keyword};
use logos::Logos;

/// A token with its byte range, as the parser wants it.
pub type Spanned<'a> = (usize, Token<'a>, usize);

/// Lexes `text` and applies the layout rule, returning the tokens and lexical diagnostics.
pub fn tokens(text: &str) -> (Vec<Spanned<'_>>, Vec<Diagnostic>) {
    let lexed = lex(text);
    (lexed.tokens, lexed.diagnostics)
}

/// The layout pass's result.
#[derive(Debug)]
pub struct Lexed<'a> {
    /// The tokens, layout included.
    pub tokens: Vec<Spanned<'a>>,
    /// Lexical and indentation diagnostics.
    pub diagnostics: Vec<Diagnostic>,
    /// Some text was not a token and was left out.
    pub dropped: bool,
}

/// Lexes `text` and applies the layout rule.
pub fn lex(text: &str) -> Lexed<'_> {
    let mut layout = Layout {
        text,
        out: Vec::with_capacity(text.len() / 3),
        diagnostics: Vec::new(),
        stack: Vec::new(),
        line_start: 0,
        line_first: None,
        asm_column: None,
        after_paren: false,
        blocks: Vec::new(),
        dropped: false,
    };
    layout.run();
    mark_tables(&mut layout.out);
    Lexed {
        tokens: layout.out,
        diagnostics: layout.diagnostics,
        dropped: layout.dropped,
    }
}

struct Layout<'a> {
    text: &'a str,
    out: Vec<Spanned<'a>>,
    diagnostics: Vec<Diagnostic>,
    /// Columns of the enclosing indentation levels.
    stack: Vec<usize>,
    /// Offset where the current physical line starts.
    line_start: usize,
    /// Index in `out` of the first token of the current logical line, if it has one.
    line_first: Option<usize>,
    /// Column of an `ASM`/`GUY` keyword whose body follows the current line.
    asm_column: Option<usize>,
    /// The current line ended with `(`: the next token may open a parenthesised block.
    after_paren: bool,
    /// Open parenthesised blocks (`(VALOF ...)` over several lines).
    blocks: Vec<Block>,
    /// Some text was not a token.
    dropped: bool,
}

/// A parenthesised block spanning lines: `(` then declarations or `VALOF` on the next lines,
/// closed by a line starting with `)`.
struct Block {
    /// Length of the indentation stack outside the block.
    depth: usize,
    /// The block's first level was announced with an `Indent` token (when `(` ended the line),
    /// rather than sharing the line of `(VALOF`.
    indented: bool,
}

impl<'a> Layout<'a> {
    fn run(&mut self) {
        let mut base = 0;
        'restart: loop {
            let mut lexer = Token::lexer(&self.text[base..]);
            while let Some(result) = lexer.next() {
                let span = lexer.span();
                let (start, end) = (base + span.start, base + span.end);
                match result {
                    Ok(Token::LineBreak) => {
                        if let Some(resume) = self.newline(start) {
                            base = resume;
                            continue 'restart;
                        }
                    }
                    Ok(token) => self.token(token, start, end),
                    Err(error) => {
                        self.dropped = true;
                        let span = Span::new(start, end);
                        let message = match error {
                            LexError::BadCharacter => {
                                format!("`{}` is not an occam token", &self.text[start..end])
                            }
                            other => other.message().to_string(),
                        };
                        let diag = Diagnostic::error(span, message, "here");
                        self.diagnostics.push(diag);
                    }
                }
            }
            break;
        }
        self.finish();
    }

    /// Handles a physical line break at `at`; returns where to resume lexing after an ASM body.
    fn newline(&mut self, at: usize) -> Option<usize> {
        self.line_start = at + 1;
        let first = self.line_first?;
        if self.out.last().is_some_and(|(_, t, _)| *t == Token::LParen) {
            self.after_paren = true;
            return None;
        }
        if self.out.last().is_some_and(|(_, t, _)| continues(t)) {
            return None;
        }
        if let Some((paren, column)) = self.block_after_paren(first) {
            self.out[paren].1 = Token::BlockOpen;
            self.blocks.push(Block {
                depth: self.stack.len(),
                indented: false,
            });
            self.stack.push(column);
        }
        self.end_line(first, at);
        let column = self.asm_column.take()?;
        let (lines, resume) = asm_body(self.text, at + 1, column);
        self.out.push((at, Token::AsmBody(lines), at));
        self.out.push((at, Token::NewLine, at));
        self.line_start = resume;
        Some(resume)
    }

    fn end_line(&mut self, first: usize, at: usize) {
        let function = self.out[first..]
            .iter()
            .position(|(_, t, _)| *t == Token::Keyword(Kw::Function));
        if let Some(function) = function {
            // The result types start the declaration: at the line's start, or after the `(` of
            // a value process (`x := (MYINT FUNCTION f () IS y :`).
            let start = self.out[first..first + function]
                .iter()
                .rposition(|(_, t, _)| matches!(t, Token::LParen | Token::BlockOpen))
                .map_or(first, |p| first + p + 1);
            // Names in array sizes (`[n]INT FUNCTION`) stay names.
            let mut depth = 0usize;
            for (_, token, _) in &mut self.out[start..first + function] {
                match token {
                    Token::LBracket => depth += 1,
                    Token::RBracket => depth = depth.saturating_sub(1),
                    Token::Name(name) if depth == 0 => *token = Token::TypeName(name),
                    _ => {}
                }
            }
        }
        let is_asm = matches!(
            self.out[first..],
            [(_, Token::Keyword(Kw::Asm | Kw::Guy), _)]
        );
        if is_asm {
            self.asm_column = Some(self.out[first].0 - self.line_start_of(self.out[first].0));
        } else {
            self.out.push((at, Token::NewLine, at));
        }
        self.line_first = None;
    }

    fn line_start_of(&self, offset: usize) -> usize {
        self.text[..offset].rfind('\n').map_or(0, |i| i + 1)
    }

    /// If the logical line starting at `first` has an unclosed `(` followed by a declaration or
    /// `VALOF` (`(VALOF` or `(INT x :`, or any line ending in the `:` of a declaration, as in
    /// `(MYINT x :` or `([3]REAL64 t :`), returns the index of that `(` and the column of the
    /// token after it: a block starts there.
    fn block_after_paren(&self, first: usize) -> Option<(usize, usize)> {
        let ends_declaration = self.out.last().is_some_and(|(_, t, _)| *t == Token::Colon);
        let mut depth = 0usize;
        for i in (first..self.out.len()).rev() {
            match self.out[i].1 {
                Token::RParen => depth += 1,
                Token::BlockOpen if depth > 0 => depth -= 1,
                Token::LParen if depth > 0 => depth -= 1,
                Token::LParen => {
                    let (at, token, _) = self.out.get(i + 1)?;
                    return (ends_declaration || opens_block(token))
                        .then(|| (i, column(&self.text[self.line_start_of(*at)..*at])));
                }
                _ => {}
            }
        }
        None
    }

    fn token(&mut self, token: Token<'a>, start: usize, end: usize) {
        let token = match token {
            Token::Name(name) => keyword(name).map_or(Token::Name(name), Token::Keyword),
            other => other,
        };
        if std::mem::take(&mut self.after_paren) && opens_block(&token) {
            if let Some(last) = self.out.last_mut() {
                last.1 = Token::BlockOpen;
            }
            self.blocks.push(Block {
                depth: self.stack.len(),
                indented: true,
            });
            self.stack.push(column(&self.text[self.line_start..start]));
            self.out.push((start, Token::Indent, start));
            self.line_first = Some(self.out.len());
        } else if self.line_first.is_none() && token == Token::RParen && !self.blocks.is_empty() {
            self.close_block(start);
            self.line_first = Some(self.out.len());
        }
        if self.line_first.is_none() {
            let column = column(&self.text[self.line_start..start]);
            self.indent(column, start);
            self.line_first = Some(self.out.len());
        }
        self.out.push((start, token, end));
    }

    /// Closes the innermost parenthesised block before its `)`.
    fn close_block(&mut self, at: usize) {
        let Some(block) = self.blocks.pop() else {
            return;
        };
        while self.stack.len() > block.depth {
            self.stack.pop();
            if block.indented || self.stack.len() > block.depth {
                self.out.push((at, Token::Dedent, at));
            }
        }
    }

    fn indent(&mut self, column: usize, at: usize) {
        let Some(&top) = self.stack.last() else {
            self.stack.push(column);
            return;
        };
        if column > top {
            if column != top + 2 {
                let span = Span::new(at, at + 1);
                let message = "this line is indented more than one level (two spaces)";
                let label = format!("expected column {}", top + 3);
                self.diagnostics
                    .push(Diagnostic::error(span, message, label).with_help(
                        "occam indents each nested level by exactly two spaces; \
                         a continued line must follow an operator, comma, `;`, `:=` or IS",
                    ));
            }
            self.stack.push(column);
            self.out.push((at, Token::Indent, at));
            return;
        }
        while self.stack.len() > 1 && self.stack.last().is_some_and(|&c| c > column) {
            self.stack.pop();
            self.out.push((at, Token::Dedent, at));
        }
        if self.stack.last() != Some(&column) {
            let span = Span::new(at, at + 1);
            let message = "this line's indentation matches no enclosing line";
            let diag = Diagnostic::error(span, message, "misaligned here")
                .with_help("line it up with the construct it belongs to (steps of two spaces)");
            self.diagnostics.push(diag);
        }
    }

    fn finish(&mut self) {
        let end = self.text.len();
        if let Some(first) = self.line_first {
            self.end_line(first, end);
            if self.asm_column.take().is_some() {
                self.out.push((end, Token::AsmBody(Vec::new()), end));
                self.out.push((end, Token::NewLine, end));
            }
        }
        while self.stack.len() > 1 {
            self.stack.pop();
            self.out.push((end, Token::Dedent, end));
        }
    }
}

/// The display column of the end of `prefix` (tabs to the next multiple of eight).
fn column(prefix: &str) -> usize {
    prefix.chars().fold(0, |col, c| match c {
        '\t' => (col / 8 + 1) * 8,
        _ => col + 1,
    })
}

/// Reports whether `token`, first on the line after a line ending in `(`, opens a block
/// (declarations or VALOF) rather than continuing an expression.
fn opens_block(token: &Token) -> bool {
    matches!(
        token,
        Token::Keyword(
            Kw::Valof
                | Kw::Val
                | Kw::Initial
                | Kw::Int
                | Kw::Int16
                | Kw::Int32
                | Kw::Int64
                | Kw::Byte
                | Kw::Bool
                | Kw::Real32
                | Kw::Real64
                | Kw::Data
                | Kw::Protocol
                | Kw::Proc
        )
    )
}

/// Reports whether a line ending in `token` continues on the next line.
fn continues(token: &Token) -> bool {
    use Token as T;
    match token {
        T::Comma | T::Semi | T::Assign | T::Plus | T::Minus | T::Star | T::Slash | T::Backslash => {
            true
        }
        T::BitAndOp | T::BitOrOp | T::XorOp | T::Shl | T::Shr | T::Eq | T::Ne | T::Lt | T::Gt => {
            true
        }
        T::Le | T::Ge | T::Amp | T::ColonColon | T::LParen | T::LBracket | T::Bar => true,
        T::UserOp(_) => true,
        T::Keyword(kw) => matches!(
            kw,
            Kw::Is
                | Kw::From
                | Kw::For
                | Kw::After
                | Kw::Retypes
                | Kw::Reshapes
                | Kw::And
                | Kw::Or
                | Kw::Plus
                | Kw::Minus
                | Kw::Times
                | Kw::Rem
                | Kw::Bitand
                | Kw::Bitor
                | Kw::Step
                | Kw::At
        ),
        _ => false,
    }
}

/// Collects the lines after `start` indented deeper than `column` (blank lines included), with
/// that indentation removed; returns them and the offset just after the last one.
fn asm_body(text: &str, start: usize, column: usize) -> (Vec<(usize, String)>, usize) {
    let mut lines = Vec::new();
    let mut at = start;
    while at < text.len() {
        let end = text[at..].find('\n').map_or(text.len(), |i| at + i);
        let line = &text[at..end];
        let indent = line.len() - line.trim_start().len();
        if !line.trim().is_empty() && indent <= column {
            break;
        }
        let kept = line.get(column + 2..).unwrap_or("");
        lines.push((end - kept.len(), kept.trim_end().to_string()));
        at = (end + 1).min(text.len());
    }
    while lines.last().is_some_and(|(_, l)| l.is_empty()) {
        lines.pop();
    }
    let resume = if at >= text.len() { text.len() } else { at - 1 };
    (lines, resume.max(start.saturating_sub(1)))
}

/// Retags the `[` of every one-element table `[x]` as `TableOpen`: a `[` that follows no operand,
/// holds no `,`, `FROM`, `FOR` or `|` at its own depth, and whose `]` is not followed by a type.
fn mark_tables(tokens: &mut [Spanned<'_>]) {
    let mut open: Vec<(usize, bool)> = Vec::new();
    for i in 0..tokens.len() {
        match &tokens[i].1 {
            Token::LBracket => {
                let after_operand = i > 0 && ends_operand(&tokens[i - 1].1);
                open.push((i, !after_operand));
            }
            Token::Comma | Token::Bar | Token::Keyword(Kw::From | Kw::For) => {
                if let Some(last) = open.last_mut() {
                    last.1 = false;
                }
            }
            Token::NewLine => open.clear(),
            Token::RBracket => {
                let Some((start, candidate)) = open.pop() else {
                    continue;
                };
                let next = tokens.get(i + 1).map(|t| &t.1);
                if candidate && i > start + 1 && !next.is_some_and(starts_type) {
                    tokens[start].1 = Token::TableOpen;
                }
            }
            _ => {}
        }
    }
}

fn ends_operand(token: &Token) -> bool {
    matches!(
        token,
        Token::Name(_)
            | Token::RBracket
            | Token::RParen
            | Token::Int(_)
            | Token::Hex(_)
            | Token::Real(_)
            | Token::Char(_)
            | Token::Str(_)
    )
}

fn starts_type(token: &Token) -> bool {
    matches!(
        token,
        Token::Name(_)
            | Token::TypeName(_)
            | Token::LBracket
            | Token::Keyword(
                Kw::Bool
                    | Kw::Byte
                    | Kw::Int
                    | Kw::Int16
                    | Kw::Int32
                    | Kw::Int64
                    | Kw::Real32
                    | Kw::Real64
                    | Kw::Timer
                    | Kw::Chan
                    | Kw::Port
            )
    )
}
