//! The occam token set (logos), with literal decoding. Layout (indentation, continuation lines)
//! is added on top by [`crate::layout`].

use logos::Logos;

use crate::ast::UserOp;

/// Why a piece of text is not a token.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum LexError {
    /// Occurs when a character cannot start any token (`$`, `` ` ``).
    #[default]
    BadCharacter,
    /// Occurs when an integer literal does not fit in 64 bits (`99999999999999999999`).
    IntegerTooLarge,
    /// Occurs when a `*` escape in a string or character is unknown (`"*q"`).
    BadEscape,
    /// Occurs when a character literal holds other than one character (`'ab'`).
    BadCharLiteral,
    /// Occurs when a string is not closed on its line (`"abc`).
    UnclosedString,
}

impl LexError {
    /// Describes the error for a person.
    pub fn message(&self) -> &'static str {
        match self {
            LexError::BadCharacter => "this character cannot appear in occam here",
            LexError::IntegerTooLarge => "this number does not fit in 64 bits",
            LexError::BadEscape => {
                "unknown escape: use *n *c *t *s *' *\" ** *#hh, or *l first in a string"
            }
            LexError::BadCharLiteral => "a character literal holds exactly one character",
            LexError::UnclosedString => {
                "this string is not closed: end it with \" or continue it with * and *"
            }
        }
    }
}

/// An occam token. Keywords are upper case; names may contain dots.
#[derive(Logos, Debug, Clone, PartialEq)]
#[logos(error = LexError)]
#[logos(skip r"[ \t\r\f]+")]
#[logos(skip(r"--[^\n]*", allow_greedy = true))]
pub enum Token<'a> {
    /// The `\n` that ends a physical line, as lexed; [`crate::layout`] turns these into
    /// [`Token::NewLine`], [`Token::Indent`] and [`Token::Dedent`] and none reaches the parser.
    #[token("\n")]
    LineBreak,
    /// The end of a logical line (made by the layout pass; continuation lines have none).
    NewLine,
    /// Indentation increased by one level.
    Indent,
    /// Indentation decreased by one level.
    Dedent,
    /// An opaque ASM/GUY body (made by the layout pass).
    AsmBody(Vec<(usize, String)>),

    /// A name (`x`, `out.string`).
    #[regex(r"[A-Za-z][A-Za-z0-9._]*", |lex| lex.slice())]
    Name(&'a str),
    /// The `[` of a one-element table `[x]` (set by the layout pass: `[x]` alone would read as
    /// the start of an array type `[x]INT`).
    TableOpen,
    /// The `(` of a VALOF expression over several lines (set by the layout pass).
    BlockOpen,
    /// A name written before `FUNCTION` on the same line, hence a type (set by the layout pass).
    TypeName(&'a str),
    /// A decimal integer.
    #[regex(r"[0-9]+", decimal)]
    Int(u64),
    /// A `#hex` integer.
    #[regex(r"#[0-9A-Fa-f]+", hex)]
    Hex(u64),
    /// A REAL literal as written.
    #[regex(r"[0-9]+\.[0-9]+([Ee][+-]?[0-9]+)?", |lex| lex.slice().to_string())]
    Real(String),
    /// A character literal.
    #[regex(r"'([^'*\n]|\*[^\n]|\*#[0-9A-Fa-f][0-9A-Fa-f])*'", character)]
    Char(u8),
    /// A string literal (possibly continued over lines with `*` ... `*`).
    #[regex(r#""([^"*\n]|\*[^\n]|\*[ \t\r]*\n[ \t]*\*)*""#, string)]
    Str(Vec<u8>),
    /// A string that reaches the end of its line.
    #[regex(r#""([^"*\n]|\*[^\n])*"#, unclosed)]
    UnclosedStr,

    #[token("(")]
    /// `(`.
    LParen,
    #[token(")")]
    /// `)`.
    RParen,
    #[token("[")]
    /// `[`.
    LBracket,
    #[token("]")]
    /// `]`.
    RBracket,
    #[token(",")]
    /// `,`.
    Comma,
    #[token(";")]
    /// `;`.
    Semi,
    #[token(":")]
    /// `:`.
    Colon,
    #[token("::")]
    /// `::`.
    ColonColon,
    #[token(":=")]
    /// `:=`.
    Assign,
    #[token("!")]
    /// `!`.
    Bang,
    #[token("?")]
    /// `?`.
    Query,
    #[token("&")]
    /// `&`.
    Amp,
    #[token("|")]
    /// `|`.
    Bar,
    #[token("+")]
    /// `+`.
    Plus,
    #[token("-")]
    /// `-`.
    Minus,
    #[token("*")]
    /// `*`.
    Star,
    #[token("/")]
    /// `/`.
    Slash,
    #[token("\\")]
    /// `\`.
    Backslash,
    #[token("/\\")]
    /// `/\`.
    BitAndOp,
    #[token("\\/")]
    /// `\/`.
    BitOrOp,
    #[token("><")]
    /// `><`.
    XorOp,
    #[token("~")]
    /// `~`.
    Tilde,
    #[token("<<")]
    /// `<<`.
    Shl,
    #[token(">>")]
    /// `>>`.
    Shr,
    #[token("=")]
    /// `=`.
    Eq,
    #[token("<>")]
    /// `<>`.
    Ne,
    #[token("<")]
    /// `<`.
    Lt,
    #[token(">")]
    /// `>`.
    Gt,
    #[token("<=")]
    /// `<=`.
    Le,
    #[token(">=")]
    /// `>=`.
    Ge,

    /// An operator with no built-in meaning, which a program may define (`a ++ b`, `?? a`).
    #[token("??", |_| UserOp::DQuery)]
    #[token("@@", |_| UserOp::DAt)]
    #[token("$$", |_| UserOp::DDollar)]
    #[token("%", |_| UserOp::Percent)]
    #[token("%%", |_| UserOp::DPercent)]
    #[token("&&", |_| UserOp::DAmp)]
    #[token("<%", |_| UserOp::LeftPercent)]
    #[token("%>", |_| UserOp::PercentRight)]
    #[token("<&", |_| UserOp::LeftAmp)]
    #[token("&>", |_| UserOp::AmpRight)]
    #[token("<]", |_| UserOp::RotLeft)]
    #[token("[>", |_| UserOp::RotRight)]
    #[token("++", |_| UserOp::DPlus)]
    #[token("^", |_| UserOp::Hat)]
    #[token("!!", |_| UserOp::DBang)]
    #[token("==", |_| UserOp::DEq)]
    #[token("<@", |_| UserOp::LeftAt)]
    #[token("@>", |_| UserOp::AtRight)]
    #[token("@", |_| UserOp::At)]
    UserOp(UserOp),

    /// A keyword (upper case, exactly as listed in [`KEYWORDS`]; made from a name by the layout
    /// pass).
    Keyword(Kw),
}

/// occam's reserved words.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[allow(missing_docs, reason = "each variant is the keyword of the same spelling")]
#[rustfmt::skip]
pub enum Kw {
    After, Alt, And, Any, Asm, At, Bitand, Bitnot, Bitor, Bool, Byte, Bytesin, Case, Chan, Data,
    Else, False, For, From, Function, Guy, If, Initial, Inline, Int, Int16, Int32, Int64, Is,
    Minus, Mostneg, Mostpos, Not, Of, Offsetof, Or, Packed, Par, Place, Placed, Plus, Port, Pri,
    Proc, Processor, Protocol, Real32, Real64, Record, Rem, Reshapes, Result, Retypes, Round,
    Seq, Size, Skip, Step, Stop, Timer, Times, True, Trunc, Type, Val, Valof, While,
}

/// Every keyword with its spelling.
#[rustfmt::skip]
pub const KEYWORDS: &[(&str, Kw)] = &[
    ("AFTER", Kw::After), ("ALT", Kw::Alt), ("AND", Kw::And), ("ANY", Kw::Any),
    ("ASM", Kw::Asm), ("AT", Kw::At), ("BITAND", Kw::Bitand), ("BITNOT", Kw::Bitnot),
    ("BITOR", Kw::Bitor), ("BOOL", Kw::Bool), ("BYTE", Kw::Byte), ("BYTESIN", Kw::Bytesin),
    ("CASE", Kw::Case), ("CHAN", Kw::Chan), ("DATA", Kw::Data), ("ELSE", Kw::Else),
    ("FALSE", Kw::False), ("FOR", Kw::For), ("FROM", Kw::From), ("FUNCTION", Kw::Function),
    ("GUY", Kw::Guy), ("IF", Kw::If), ("INITIAL", Kw::Initial), ("INLINE", Kw::Inline),
    ("INT", Kw::Int), ("INT16", Kw::Int16), ("INT32", Kw::Int32), ("INT64", Kw::Int64),
    ("IS", Kw::Is), ("MINUS", Kw::Minus), ("MOSTNEG", Kw::Mostneg), ("MOSTPOS", Kw::Mostpos),
    ("NOT", Kw::Not), ("OF", Kw::Of), ("OFFSETOF", Kw::Offsetof), ("OR", Kw::Or),
    ("PACKED", Kw::Packed), ("PAR", Kw::Par), ("PLACE", Kw::Place), ("PLACED", Kw::Placed),
    ("PLUS", Kw::Plus), ("PORT", Kw::Port), ("PRI", Kw::Pri), ("PROC", Kw::Proc),
    ("PROCESSOR", Kw::Processor), ("PROTOCOL", Kw::Protocol), ("REAL32", Kw::Real32),
    ("REAL64", Kw::Real64), ("RECORD", Kw::Record), ("REM", Kw::Rem), ("RESHAPES", Kw::Reshapes),
    ("RESULT", Kw::Result), ("RETYPES", Kw::Retypes), ("ROUND", Kw::Round), ("SEQ", Kw::Seq),
    ("SIZE", Kw::Size), ("SKIP", Kw::Skip), ("STEP", Kw::Step), ("STOP", Kw::Stop),
    ("TIMER", Kw::Timer), ("TIMES", Kw::Times), ("TRUE", Kw::True), ("TRUNC", Kw::Trunc),
    ("TYPE", Kw::Type), ("VAL", Kw::Val), ("VALOF", Kw::Valof), ("WHILE", Kw::While),
];

impl Kw {
    /// Returns the keyword's spelling.
    pub fn text(self) -> &'static str {
        KEYWORDS
            .iter()
            .find(|(_, k)| *k == self)
            .map_or("?", |(s, _)| s)
    }
}

/// Returns the keyword spelled `word`, if it is one.
pub fn keyword(word: &str) -> Option<Kw> {
    if !word.as_bytes().first().is_some_and(u8::is_ascii_uppercase) {
        return None;
    }
    Some(match word {
        "AFTER" => Kw::After,
        "ALT" => Kw::Alt,
        "AND" => Kw::And,
        "ANY" => Kw::Any,
        "ASM" => Kw::Asm,
        "AT" => Kw::At,
        "BITAND" => Kw::Bitand,
        "BITNOT" => Kw::Bitnot,
        "BITOR" => Kw::Bitor,
        "BOOL" => Kw::Bool,
        "BYTE" => Kw::Byte,
        "BYTESIN" => Kw::Bytesin,
        "CASE" => Kw::Case,
        "CHAN" => Kw::Chan,
        "DATA" => Kw::Data,
        "ELSE" => Kw::Else,
        "FALSE" => Kw::False,
        "FOR" => Kw::For,
        "FROM" => Kw::From,
        "FUNCTION" => Kw::Function,
        "GUY" => Kw::Guy,
        "IF" => Kw::If,
        "INITIAL" => Kw::Initial,
        "INLINE" => Kw::Inline,
        "INT" => Kw::Int,
        "INT16" => Kw::Int16,
        "INT32" => Kw::Int32,
        "INT64" => Kw::Int64,
        "IS" => Kw::Is,
        "MINUS" => Kw::Minus,
        "MOSTNEG" => Kw::Mostneg,
        "MOSTPOS" => Kw::Mostpos,
        "NOT" => Kw::Not,
        "OF" => Kw::Of,
        "OFFSETOF" => Kw::Offsetof,
        "OR" => Kw::Or,
        "PACKED" => Kw::Packed,
        "PAR" => Kw::Par,
        "PLACE" => Kw::Place,
        "PLACED" => Kw::Placed,
        "PLUS" => Kw::Plus,
        "PORT" => Kw::Port,
        "PRI" => Kw::Pri,
        "PROC" => Kw::Proc,
        "PROCESSOR" => Kw::Processor,
        "PROTOCOL" => Kw::Protocol,
        "REAL32" => Kw::Real32,
        "REAL64" => Kw::Real64,
        "RECORD" => Kw::Record,
        "REM" => Kw::Rem,
        "RESHAPES" => Kw::Reshapes,
        "RESULT" => Kw::Result,
        "RETYPES" => Kw::Retypes,
        "ROUND" => Kw::Round,
        "SEQ" => Kw::Seq,
        "SIZE" => Kw::Size,
        "SKIP" => Kw::Skip,
        "STEP" => Kw::Step,
        "STOP" => Kw::Stop,
        "TIMER" => Kw::Timer,
        "TIMES" => Kw::Times,
        "TRUE" => Kw::True,
        "TRUNC" => Kw::Trunc,
        "TYPE" => Kw::Type,
        "VAL" => Kw::Val,
        "VALOF" => Kw::Valof,
        "WHILE" => Kw::While,
        _ => return None,
    })
}

fn decimal<'a>(lex: &mut logos::Lexer<'a, Token<'a>>) -> Result<u64, LexError> {
    lex.slice().parse().map_err(|_| LexError::IntegerTooLarge)
}

fn hex<'a>(lex: &mut logos::Lexer<'a, Token<'a>>) -> Result<u64, LexError> {
    u64::from_str_radix(&lex.slice()[1..], 16).map_err(|_| LexError::IntegerTooLarge)
}

fn character<'a>(lex: &mut logos::Lexer<'a, Token<'a>>) -> Result<u8, LexError> {
    let slice = lex.slice();
    let bytes = unescape(&slice[1..slice.len() - 1])?;
    match bytes.as_slice() {
        [b] => Ok(*b),
        _ => Err(LexError::BadCharLiteral),
    }
}

fn string<'a>(lex: &mut logos::Lexer<'a, Token<'a>>) -> Result<Vec<u8>, LexError> {
    let slice = lex.slice();
    unescape(&slice[1..slice.len() - 1])
}

/// Resolves occam `*` escapes, and joins `*` newline ... `*` string continuations.
pub fn unescape(body: &str) -> Result<Vec<u8>, LexError> {
    let bytes = body.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let b = bytes[i];
        i += 1;
        if b != b'*' {
            out.push(b);
            continue;
        }
        let e = *bytes.get(i).ok_or(LexError::BadEscape)?;
        i += 1;
        match e {
            b'n' | b'N' => out.push(b'\n'),
            b'c' | b'C' => out.push(b'\r'),
            b't' | b'T' => out.push(b'\t'),
            b's' | b'S' => out.push(b' '),
            b'\'' | b'"' | b'*' => out.push(e),
            b'#' => {
                let digits = body.get(i..i + 2).ok_or(LexError::BadEscape)?;
                out.push(u8::from_str_radix(digits, 16).map_err(|_| LexError::BadEscape)?);
                i += 2;
            }
            b' ' | b'\t' | b'\r' | b'\n' => i = skip_continuation(bytes, i - 1)?,
            // `*l` first in a string stands for its length (the bytes after it).
            b'l' | b'L' if i == 2 => out.push(0),
            _ => return Err(LexError::BadEscape),
        }
    }
    if body.starts_with("*l") || body.starts_with("*L") {
        out[0] = u8::try_from(out.len() - 1).map_err(|_| LexError::BadEscape)?;
    }
    Ok(out)
}

/// Skips from the whitespace after a continuation `*` to just past the `*` that resumes the
/// string on the next line.
fn skip_continuation(bytes: &[u8], mut i: usize) -> Result<usize, LexError> {
    let mut saw_newline = false;
    while let Some(&b) = bytes.get(i) {
        match b {
            b'\n' => saw_newline = true,
            b' ' | b'\t' | b'\r' => {}
            b'*' if saw_newline => return Ok(i + 1),
            _ => break,
        }
        i += 1;
    }
    Err(LexError::BadEscape)
}

fn unclosed<'a>(_: &mut logos::Lexer<'a, Token<'a>>) -> Result<(), LexError> {
    Err(LexError::UnclosedString)
}
