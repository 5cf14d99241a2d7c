//! Lexer tables: one line per case, asserting token kinds (after the layout pass).

use occ_grammar::lexer::{Kw, Token};

fn kinds(text: &str) -> Vec<Token<'_>> {
    let (tokens, diags) = occ_grammar::layout::tokens(text);
    assert!(diags.is_empty(), "{text:?}: {diags:?}");
    tokens.into_iter().map(|(_, t, _)| t).collect()
}

fn lex_error(text: &str) -> bool {
    !occ_grammar::layout::tokens(text).1.is_empty()
}

macro_rules! lex {
    ($name:ident, $text:expr, [$($token:expr),* $(,)?]) => {
        #[test]
        fn $name() {
            assert_eq!(kinds($text), vec![$($token),*]);
        }
    };
}

macro_rules! lexerr {
    ($name:ident, $text:expr) => {
        #[test]
        fn $name() {
            assert!(lex_error($text), "{:?} should not lex", $text);
        }
    };
}

use Token::*;
const NL: Token = NewLine;

lex!(decimal, "42", [Int(42), NL]);
lex!(hex, "#FF", [Hex(255), NL]);
lex!(hex_lower, "#ff", [Hex(255), NL]);
lex!(real, "1.5", [Real("1.5".into()), NL]);
lex!(real_exponent, "1.0E+3", [Real("1.0E+3".into()), NL]);
lex!(
    real_negative_exponent,
    "2.5e-7",
    [Real("2.5e-7".into()), NL]
);
lex!(char_plain, "'a'", [Char(b'a'), NL]);
lex!(char_escape_newline, "'*n'", [Char(b'\n'), NL]);
lex!(char_escape_quote, "'*''", [Char(b'\''), NL]);
lex!(char_escape_hex, "'*#41'", [Char(b'A'), NL]);
lex!(
    string_escapes,
    r#""a*c*n*t*s*"**""#,
    [Str(b"a\r\n\t \"*".to_vec()), NL]
);
lex!(string_hex_escape, r#""*#7F""#, [Str(vec![0x7f]), NL]);
lex!(
    string_continued,
    "\"abc*\n    *def\"",
    [Str(b"abcdef".to_vec()), NL]
);
lex!(
    typed_literal,
    "5(INT64)",
    [Int(5), LParen, Keyword(Kw::Int64), RParen, NL]
);
lex!(dotted_name, "out.string", [Name("out.string"), NL]);
lex!(
    keyword_prefix_name,
    "INT.TO.STRING",
    [Name("INT.TO.STRING"), NL]
);
lex!(keyword, "SEQ", [Keyword(Kw::Seq), NL]);
lex!(lowercase_is_name, "seq", [Name("seq"), NL]);
lex!(
    comment_ignored,
    "SKIP -- a comment",
    [Keyword(Kw::Skip), NL]
);
lex!(
    operators,
    r"+ - * / \ /\ \/ >< << >> <> <= >= ~",
    [
        Plus, Minus, Star, Slash, Backslash, BitAndOp, BitOrOp, XorOp, Shl, Shr, Ne, Le, Ge, Tilde,
        NL
    ]
);
lex!(
    assign_and_colons,
    "x := a :: b :",
    [
        Name("x"),
        Assign,
        Name("a"),
        ColonColon,
        Name("b"),
        Colon,
        NL
    ]
);
lex!(
    indent_dedent,
    "SEQ\n  SKIP\nSTOP",
    [
        Keyword(Kw::Seq),
        NL,
        Indent,
        Keyword(Kw::Skip),
        NL,
        Dedent,
        Keyword(Kw::Stop),
        NL
    ]
);
lex!(
    blank_and_comment_lines_ignored,
    "SEQ\n\n  -- c\n  SKIP",
    [Keyword(Kw::Seq), NL, Indent, Keyword(Kw::Skip), NL, Dedent]
);
lex!(
    continuation_after_operator,
    "x := a +\n       b",
    [Name("x"), Assign, Name("a"), Plus, Name("b"), NL]
);
lex!(
    continuation_after_comma,
    "f (a,\n   b)",
    [Name("f"), LParen, Name("a"), Comma, Name("b"), RParen, NL]
);
lex!(
    continuation_after_is,
    "VAL x IS\n  3 :",
    [
        Keyword(Kw::Val),
        Name("x"),
        Keyword(Kw::Is),
        Int(3),
        Colon,
        NL
    ]
);
lex!(
    function_result_names_are_types,
    "MY, INT FUNCTION f (MY x)",
    [
        TypeName("MY"),
        Comma,
        Keyword(Kw::Int),
        Keyword(Kw::Function),
        Name("f"),
        LParen,
        Name("MY"),
        Name("x"),
        RParen,
        NL
    ]
);
lex!(
    one_element_table,
    "x := [y]",
    [Name("x"), Assign, TableOpen, Name("y"), RBracket, NL]
);
lex!(
    array_type_not_table,
    "[4]INT x:",
    [
        LBracket,
        Int(4),
        RBracket,
        Keyword(Kw::Int),
        Name("x"),
        Colon,
        NL
    ]
);
lex!(
    subscript_not_table,
    "a[i]",
    [Name("a"), LBracket, Name("i"), RBracket, NL]
);
lex!(
    tab_is_eight_columns,
    "SEQ\n  SEQ\n    SEQ\n      SEQ\n\tSKIP",
    [
        Keyword(Kw::Seq),
        NL,
        Indent,
        Keyword(Kw::Seq),
        NL,
        Indent,
        Keyword(Kw::Seq),
        NL,
        Indent,
        Keyword(Kw::Seq),
        NL,
        Indent,
        Keyword(Kw::Skip),
        NL,
        Dedent,
        Dedent,
        Dedent,
        Dedent
    ]
);

lexerr!(bad_character, "x := $");
lexerr!(bad_escape, r#""*q""#);
lexerr!(unclosed_string, "\"abc");
lexerr!(two_char_literal, "'ab'");
lexerr!(integer_too_large, "99999999999999999999999");
lexerr!(three_space_indent, "SEQ\n   SKIP");
lexerr!(misaligned_outdent, "SEQ\n  SEQ\n    SKIP\n   SKIP");
