//! The pretty-printer: AST → occam text that parses back to the same AST (spans aside).
//!
//! Nested operator expressions are always parenthesised, so occam's "no precedence" rule holds
//! in the output; declarations and processes use two-space indentation.

use crate::ast::*;
use crate::lexer::Token;
use std::fmt::Write;

/// Prints a whole program.
pub fn program(p: &Program) -> String {
    let mut printer = Printer::default();
    for d in &p.decls {
        printer.decl(d);
    }
    printer.out
}

/// Prints one expression (a VALOF expression spans several lines).
pub fn expr_text(e: &Expr) -> String {
    expr(e).replace(BREAK, "\n  ")
}

/// Prints one expression for use inside a line: the printer's `line` indents any breaks.
fn expr(e: &Expr) -> String {
    let mut s = String::new();
    write_expr(&mut s, e);
    s
}

/// Prints one type.
pub fn ty(t: &Ty) -> String {
    let mut s = String::new();
    write_ty(&mut s, t);
    s
}

/// The spelling of a dyadic operator.
pub fn binop_text(op: BinOp) -> &'static str {
    use BinOp::*;
    match op {
        Add => "+",
        Sub => "-",
        Mul => "*",
        Div => "/",
        Rem => "\\",
        Plus => "PLUS",
        Minus => "MINUS",
        Times => "TIMES",
        BitAnd => "/\\",
        BitOr => "\\/",
        Xor => "><",
        Shl => "<<",
        Shr => ">>",
        And => "AND",
        Or => "OR",
        Eq => "=",
        Ne => "<>",
        Lt => "<",
        Gt => ">",
        Le => "<=",
        Ge => ">=",
        After => "AFTER",
        User(u) => u.text(),
    }
}

/// The spelling of a monadic operator.
pub fn unop_text(op: UnOp) -> &'static str {
    match op {
        UnOp::Neg => "-",
        UnOp::Minus => "MINUS",
        UnOp::BitNot => "~",
        UnOp::Not => "NOT",
        UnOp::User(u) => u.text(),
    }
}

/// The spelling of a punctuation token (for messages).
pub fn token_text(token: &Token) -> &'static str {
    use Token as T;
    match token {
        T::LParen => "(",
        T::RParen => ")",
        T::LBracket => "[",
        T::RBracket => "]",
        T::Comma => ",",
        T::Semi => ";",
        T::Colon => ":",
        T::ColonColon => "::",
        T::Assign => ":=",
        T::Bang => "!",
        T::Query => "?",
        T::Amp => "&",
        T::Bar => "|",
        T::Plus => "+",
        T::Minus => "-",
        T::Star => "*",
        T::Slash => "/",
        T::Backslash => "\\",
        T::BitAndOp => "/\\",
        T::BitOrOp => "\\/",
        T::XorOp => "><",
        T::Tilde => "~",
        T::Shl => "<<",
        T::Shr => ">>",
        T::Eq => "=",
        T::Ne => "<>",
        T::Lt => "<",
        T::Gt => ">",
        T::Le => "<=",
        T::Ge => ">=",
        T::UserOp(u) => u.text(),
        _ => "token",
    }
}

/// A line break inside a printed expression, indented by whoever prints the enclosing line.
const BREAK: &str = "\n\u{1}";

#[derive(Default)]
struct Printer {
    out: String,
    depth: usize,
}

impl Printer {
    fn line(&mut self, text: &str) {
        let indent = "  ".repeat(self.depth);
        self.out.push_str(&indent);
        self.out
            .push_str(&text.replace(BREAK, &format!("\n{indent}  ")));
        self.out.push('\n');
    }

    fn nested(&mut self, f: impl FnOnce(&mut Self)) {
        self.depth += 1;
        f(self);
        self.depth -= 1;
    }

    fn decls(&mut self, decls: &[Decl]) {
        for d in decls {
            self.decl(d);
        }
    }

    fn decl(&mut self, d: &Decl) {
        match &d.kind {
            DeclKind::Var { ty, names } => self.line(&format!("{} {}:", ty_s(ty), names_s(names))),
            DeclKind::Abbrev {
                mode,
                ty,
                name,
                dir,
                value,
            } => {
                let kw = match mode {
                    AbbrevMode::Val => "VAL ",
                    AbbrevMode::Ref => "",
                    AbbrevMode::Result => "RESULT ",
                    AbbrevMode::Initial => "INITIAL ",
                };
                let ty = ty
                    .as_ref()
                    .map(|t| format!("{} ", ty_s(t)))
                    .unwrap_or_default();
                let text = format!("{kw}{ty}{}{} IS {}:", name.text, dir_s(*dir), expr(value));
                self.line(&text)
            }
            DeclKind::Retypes {
                kind,
                val,
                ty,
                name,
                value,
            } => {
                let kw = if *val { "VAL " } else { "" };
                let op = match kind {
                    RetypeKind::Retypes => "RETYPES",
                    RetypeKind::Reshapes => "RESHAPES",
                };
                self.line(&format!(
                    "{kw}{} {} {op} {}:",
                    ty_s(ty),
                    name.text,
                    expr(value)
                ))
            }
            DeclKind::DataType { name, def } => self.data_type(name, def),
            DeclKind::Protocol { name, def } => self.protocol(name, def),
            DeclKind::Proc {
                name,
                inline,
                params,
                body,
            } => {
                let inline = if *inline { "INLINE " } else { "" };
                self.line(&format!(
                    "{inline}PROC {} ({})",
                    name.text,
                    params_s(params)
                ));
                self.nested(|p| p.process(body));
                self.line(":");
            }
            DeclKind::Function {
                name,
                inline,
                results,
                params,
                body,
            } => self.function(name, *inline, results, params, body),
            DeclKind::Place { name, at } => {
                self.line(&format!("PLACE {} AT {}:", name.text, expr(at)))
            }
            DeclKind::Asm(block) => self.asm(block),
            DeclKind::PlaceIn { name, area } => {
                self.line(&format!("PLACE {} IN {}:", name.text, area.text))
            }
        }
    }

    fn data_type(&mut self, name: &Name, def: &DataTypeDef) {
        match def {
            DataTypeDef::Alias(t) => self.line(&format!("DATA TYPE {} IS {}:", name.text, ty_s(t))),
            DataTypeDef::Record { packed, fields } => {
                self.line(&format!("DATA TYPE {}", name.text));
                self.nested(|p| {
                    p.line(if *packed { "PACKED RECORD" } else { "RECORD" });
                    p.nested(|p| {
                        for f in fields {
                            p.line(&format!("{} {}:", ty_s(&f.ty), names_s(&f.names)));
                        }
                    });
                });
                self.line(":");
            }
        }
    }

    fn protocol(&mut self, name: &Name, def: &ProtocolDef) {
        match def {
            ProtocolDef::Sequential(items) => {
                let items: Vec<String> = items.iter().map(proto_s).collect();
                self.line(&format!("PROTOCOL {} IS {}:", name.text, items.join("; ")));
            }
            ProtocolDef::Tagged(cases) => {
                self.line(&format!("PROTOCOL {}", name.text));
                self.nested(|p| {
                    p.line("CASE");
                    p.nested(|p| {
                        for c in cases {
                            let mut text = c.tag.text.clone();
                            for item in &c.items {
                                let _ = write!(text, "; {}", proto_s(item));
                            }
                            p.line(&text);
                        }
                    });
                });
                self.line(":");
            }
        }
    }

    fn function(
        &mut self,
        name: &Name,
        inline: bool,
        results: &[Ty],
        params: &[Param],
        body: &FunctionBody,
    ) {
        let results: Vec<String> = results.iter().map(ty_s).collect();
        let inline = if inline { "INLINE " } else { "" };
        // An operator's name (`"+"`, `"PLUS"`) is written as a string.
        let is_name = name.text.starts_with(|c: char| c.is_ascii_alphabetic())
            && crate::lexer::keyword(&name.text).is_none();
        let shown = if is_name {
            name.text.clone()
        } else {
            let mut quoted = String::new();
            literal(
                &mut quoted,
                &Literal {
                    kind: LitKind::String(name.text.clone().into_bytes()),
                    ty: None,
                },
            );
            quoted
        };
        let head = format!(
            "{} {inline}FUNCTION {shown} ({})",
            results.join(", "),
            params_s(params)
        );
        match body {
            FunctionBody::Is(values) => self.line(&format!("{head} IS {}:", exprs_s(values))),
            FunctionBody::Valof(v) => {
                self.line(&head);
                self.nested(|p| p.valof(v));
                self.line(":");
            }
        }
    }

    fn valof(&mut self, v: &Valof) {
        self.decls(&v.decls);
        self.line("VALOF");
        self.nested(|p| {
            p.process(&v.body);
            p.line(&format!("RESULT {}", exprs_s(&v.results)));
        });
    }

    fn asm(&mut self, block: &AsmBlock) {
        self.line(if block.guy { "GUY" } else { "ASM" });
        self.nested(|p| {
            for l in &block.lines {
                p.line(l);
            }
        });
    }

    fn body(&mut self, head: &str, body: &Process) {
        self.line(head);
        self.nested(|p| p.process(body));
    }

    fn process(&mut self, p: &Process) {
        match &p.kind {
            ProcessKind::Skip => self.line("SKIP"),
            ProcessKind::Stop => self.line("STOP"),
            ProcessKind::Scope { decls, body } => {
                self.decls(decls);
                self.process(body);
            }
            ProcessKind::Assign { lhs, rhs } => {
                self.line(&format!("{} := {}", exprs_s(lhs), exprs_s(rhs)))
            }
            ProcessKind::Output { chan, items } => {
                self.line(&format!("{} ! {}", expr(chan), items_s(items)))
            }
            ProcessKind::Input { chan, items } => {
                self.line(&format!("{} ? {}", expr(chan), items_s(items)))
            }
            ProcessKind::Extended { input, .. } if input.is_held_case() => self.held_case(input),
            ProcessKind::Extended {
                input,
                during,
                after,
            } => {
                self.line(&extended_s(input));
                self.nested(|p| {
                    p.process(during);
                    if let Some(after) = after {
                        p.process(after);
                    }
                });
            }
            ProcessKind::CaseInput { chan, variants } => {
                self.line(&format!("{} ? CASE", expr(chan)));
                self.nested(|p| p.variants(variants));
            }
            ProcessKind::Delay { timer, time } => {
                self.line(&format!("{} ? AFTER {}", expr(timer), expr(time)))
            }
            ProcessKind::Seq { repl, body } => self.construct("SEQ", repl.as_deref(), body),
            ProcessKind::Par {
                pri,
                placed,
                repl,
                body,
            } => {
                let kw = match (pri, placed) {
                    (true, _) => "PRI PAR",
                    (_, true) => "PLACED PAR",
                    _ => "PAR",
                };
                self.construct(kw, repl.as_deref(), body)
            }
            ProcessKind::Processor { number, body } => {
                self.body(&format!("PROCESSOR {}", expr(number)), body)
            }
            ProcessKind::If { repl, choices } => self.if_(repl.as_deref(), choices),
            ProcessKind::Alt(alt) => self.alt(alt),
            ProcessKind::Case { selector, options } => {
                self.line(&format!("CASE {}", expr(selector)));
                self.nested(|p| p.options(options));
            }
            ProcessKind::While { cond, body } => self.body(&format!("WHILE {}", expr(cond)), body),
            ProcessKind::Call { name, args } => {
                self.line(&format!("{} ({})", name.text, exprs_s(args)))
            }
            ProcessKind::Asm(block) => self.asm(block),
        }
    }

    fn construct(&mut self, kw: &str, repl: Option<&Replicator>, body: &[Process]) {
        match repl {
            Some(r) => self.line(&format!("{kw} {}", repl_s(r))),
            None => self.line(kw),
        }
        self.nested(|p| {
            for b in body {
                p.process(b);
            }
        });
    }

    fn variants(&mut self, variants: &[Variant]) {
        for v in variants {
            self.decls(&v.decls);
            let mut head = v.tag.text.clone();
            for item in &v.items {
                let _ = write!(head, "; {}", item_s(item));
            }
            match v.body.held_parts() {
                Some((during, after)) => {
                    self.line(&head);
                    self.nested(|p| {
                        p.process(during);
                        if let Some(after) = after {
                            p.process(after);
                        }
                    });
                }
                None => self.body(&head, &v.body),
            }
        }
    }

    /// `c ?? CASE` with indented variants (its input; see [`Process::is_held_case`]), written
    /// after `prefix` (an ALT guard's condition).
    fn held_case_with(&mut self, prefix: &str, input: &Process) {
        if let ProcessKind::CaseInput { chan, variants } = &input.kind {
            self.line(&format!("{prefix}{} ?? CASE", expr(chan)));
            self.nested(|p| p.variants(variants));
        }
    }

    fn held_case(&mut self, input: &Process) {
        self.held_case_with("", input);
    }

    fn if_(&mut self, repl: Option<&Replicator>, choices: &[Choice]) {
        match repl {
            Some(r) => self.line(&format!("IF {}", repl_s(r))),
            None => self.line("IF"),
        }
        self.nested(|p| {
            for c in choices {
                p.decls(&c.decls);
                match &c.kind {
                    ChoiceKind::Guarded { cond, body } => p.body(&expr(cond), body),
                    ChoiceKind::Nested(nested) => p.process(nested),
                }
            }
        });
    }

    fn alt(&mut self, alt: &Alt) {
        let kw = if alt.pri { "PRI ALT" } else { "ALT" };
        match &alt.repl {
            Some(r) => self.line(&format!("{kw} {}", repl_s(r))),
            None => self.line(kw),
        }
        self.nested(|p| {
            for a in &alt.alternatives {
                p.decls(&a.decls);
                p.alternative(&a.kind);
            }
        });
    }

    fn alternative(&mut self, kind: &AltKind) {
        let cond_s = |c: &Option<Expr>| {
            c.as_ref()
                .map(|c| format!("{} & ", expr(c)))
                .unwrap_or_default()
        };
        match kind {
            AltKind::Guarded { cond, guard, .. } if matches!(&guard.kind, ProcessKind::Extended { input, .. } if input.is_held_case()) => {
                if let ProcessKind::Extended { input, .. } = &guard.kind {
                    self.held_case_with(&cond_s(cond), input);
                }
            }
            AltKind::Guarded { cond, guard, body } => {
                if let ProcessKind::Extended { input, during, .. } = &guard.kind {
                    self.line(&format!("{}{}", cond_s(cond), extended_s(input)));
                    self.nested(|p| {
                        p.process(during);
                        p.process(body);
                    });
                    return;
                }
                let guard = match &guard.kind {
                    ProcessKind::Input { chan, items } => {
                        format!("{} ? {}", expr(chan), items_s(items))
                    }
                    ProcessKind::Delay { timer, time } => {
                        format!("{} ? AFTER {}", expr(timer), expr(time))
                    }
                    ProcessKind::CaseInput { chan, variants } => match variants.as_slice() {
                        [v] => {
                            let mut text = format!("{} ? CASE {}", expr(chan), v.tag.text);
                            for item in &v.items {
                                let _ = write!(text, "; {}", item_s(item));
                            }
                            text
                        }
                        _ => "SKIP".to_string(),
                    },
                    _ => "SKIP".to_string(),
                };
                self.body(&format!("{}{guard}", cond_s(cond)), body);
            }
            AltKind::CaseInput {
                cond,
                chan,
                variants,
            } => {
                self.line(&format!("{}{} ? CASE", cond_s(cond), expr(chan)));
                self.nested(|p| p.variants(variants));
            }
            AltKind::Nested(alt) => self.alt(alt),
        }
    }

    fn options(&mut self, options: &[CaseOption]) {
        for o in options {
            self.decls(&o.decls);
            let head = match &o.values {
                Some(values) => exprs_s(values),
                None => "ELSE".to_string(),
            };
            self.body(&head, &o.body);
        }
    }
}

fn names_s(names: &[Name]) -> String {
    let names: Vec<&str> = names.iter().map(|n| n.text.as_str()).collect();
    names.join(", ")
}

fn dir_s(dir: Option<Direction>) -> &'static str {
    match dir {
        Some(Direction::Input) => "?",
        Some(Direction::Output) => "!",
        None => "",
    }
}

fn params_s(params: &[Param]) -> String {
    let params: Vec<String> = params
        .iter()
        .map(|p| {
            let mode = match p.mode {
                ParamMode::Val => "VAL ",
                ParamMode::Ref => "",
                ParamMode::Result => "RESULT ",
            };
            format!("{mode}{} {}{}", ty_s(&p.ty), p.name.text, dir_s(p.dir))
        })
        .collect();
    params.join(", ")
}

fn repl_s(r: &Replicator) -> String {
    let mut s = format!("{} = {} FOR {}", r.name.text, expr(&r.base), expr(&r.count));
    if let Some(step) = &r.step {
        let _ = write!(s, " STEP {}", expr(step));
    }
    s
}

fn exprs_s(es: &[Expr]) -> String {
    let es: Vec<String> = es.iter().map(expr).collect();
    es.join(", ")
}

fn item_s(item: &IoItem) -> String {
    match item {
        IoItem::Expr(e) => expr(e),
        IoItem::Counted { count, data } => format!("{} :: {}", expr(count), expr(data)),
    }
}

fn items_s(items: &[IoItem]) -> String {
    let items: Vec<String> = items.iter().map(item_s).collect();
    items.join("; ")
}

fn proto_s(item: &ProtoItem) -> String {
    match &item.kind {
        ProtoItemKind::Any => "ANY".to_string(),
        ProtoItemKind::Type(t) => ty_s(t),
        ProtoItemKind::Counted { count, elem } => format!("{}::{}", ty_s(count), ty_s(elem)),
    }
}

fn ty_s(t: &Ty) -> String {
    ty(t)
}

fn write_ty(s: &mut String, t: &Ty) {
    let text = match &t.kind {
        TyKind::Bool => "BOOL",
        TyKind::Byte => "BYTE",
        TyKind::Int => "INT",
        TyKind::Int16 => "INT16",
        TyKind::Int32 => "INT32",
        TyKind::Int64 => "INT64",
        TyKind::Real32 => "REAL32",
        TyKind::Real64 => "REAL64",
        TyKind::Timer => "TIMER",
        TyKind::Named(n) => &n.text,
        TyKind::Array { len, elem } => {
            s.push('[');
            if let Some(len) = len {
                write_expr(s, len);
            }
            s.push(']');
            return write_ty(s, elem);
        }
        TyKind::Chan(p) => {
            s.push_str("CHAN OF ");
            s.push_str(&proto_s(p));
            return;
        }
        TyKind::Port(t) => {
            s.push_str("PORT OF ");
            return write_ty(s, t);
        }
    };
    s.push_str(text);
}

/// Whether an expression prints as one operand (needs no parentheses around it).
fn is_operand(e: &Expr) -> bool {
    !matches!(
        e.kind,
        ExprKind::Binary { .. }
            | ExprKind::Unary { .. }
            | ExprKind::Conversion { .. }
            | ExprKind::MostPos(_)
            | ExprKind::MostNeg(_)
            | ExprKind::Size(_)
            | ExprKind::Directed { .. }
    )
}

fn operand(s: &mut String, e: &Expr) {
    if is_operand(e) {
        write_expr(s, e);
    } else {
        s.push('(');
        write_expr(s, e);
        s.push(')');
    }
}

fn write_expr(s: &mut String, e: &Expr) {
    match &e.kind {
        ExprKind::Literal(lit) => literal(s, lit),
        ExprKind::Name(n) => s.push_str(&n.text),
        ExprKind::Subscript { base, index } => {
            operand(s, base);
            s.push('[');
            write_expr(s, index);
            s.push(']');
        }
        ExprKind::Slice { base, from, count } => {
            s.push('[');
            write_expr(s, base);
            if let Some(from) = from {
                s.push_str(" FROM ");
                write_expr(s, from);
            }
            if let Some(count) = count {
                s.push_str(" FOR ");
                write_expr(s, count);
            }
            s.push(']');
        }
        ExprKind::Unary { op, operand: o } => {
            s.push_str(unop_text(*op));
            s.push(' ');
            operand(s, o);
        }
        ExprKind::Binary { op, lhs, rhs } => {
            operand(s, lhs);
            let _ = write!(s, " {} ", binop_text(*op));
            operand(s, rhs);
        }
        ExprKind::Conversion {
            ty,
            mode,
            operand: o,
        } => {
            write_ty(s, ty);
            s.push_str(match mode {
                ConvMode::Plain => " ",
                ConvMode::Round => " ROUND ",
                ConvMode::Trunc => " TRUNC ",
            });
            operand(s, o);
        }
        ExprKind::MostPos(t) => {
            s.push_str("MOSTPOS ");
            write_ty(s, t);
        }
        ExprKind::MostNeg(t) => {
            s.push_str("MOSTNEG ");
            write_ty(s, t);
        }
        ExprKind::Size(x) => {
            s.push_str("SIZE ");
            type_or_expr(s, x);
        }
        ExprKind::BytesIn(x) => {
            s.push_str("BYTESIN (");
            match &**x {
                TypeOrExpr::Type(t) => write_ty(s, t),
                TypeOrExpr::Expr(e) => write_expr(s, e),
            }
            s.push(')');
        }
        ExprKind::OffsetOf { ty, field } => {
            s.push_str("OFFSETOF (");
            write_ty(s, ty);
            let _ = write!(s, ", {})", field.text);
        }
        ExprKind::Call { name, args } => {
            let _ = write!(s, "{} ({})", name.text, exprs_s(args));
        }
        ExprKind::Table(items) => {
            let _ = write!(s, "[{}]", exprs_s(items));
        }
        ExprKind::List(items) => {
            let _ = write!(s, "({})", exprs_s(items));
        }
        ExprKind::TypedTable { items, ty } => {
            let _ = write!(s, "[{}](", exprs_s(items));
            write_ty(s, ty);
            s.push(')');
        }
        ExprKind::Constructor { repl, value } => {
            let _ = write!(s, "[{} | {}]", repl_s(repl), expr(value));
        }
        ExprKind::Valof(v) => {
            // `(` ends the line; the VALOF block follows on marked lines that the enclosing
            // printer indents (see `Printer::line`), then `)` on a line of its own.
            let mut inner = Printer::default();
            inner.valof(v);
            s.push('(');
            for line in inner.out.lines() {
                s.push_str(BREAK);
                s.push_str("  ");
                s.push_str(line);
            }
            s.push_str(BREAK);
            s.push(')');
        }
        ExprKind::Directed { chan, dir } => {
            write_expr(s, chan);
            s.push_str(dir_s(Some(*dir)));
        }
    }
}

fn type_or_expr(s: &mut String, x: &TypeOrExpr) {
    match x {
        TypeOrExpr::Type(t) => write_ty(s, t),
        TypeOrExpr::Expr(e) => operand(s, e),
    }
}

fn literal(s: &mut String, lit: &Literal) {
    match &lit.kind {
        LitKind::Int { value, hex: false } => {
            let _ = write!(s, "{value}");
        }
        LitKind::Int { value, hex: true } => {
            let _ = write!(s, "#{value:X}");
        }
        LitKind::Byte(b) => {
            s.push('\'');
            escape(s, *b, b'\'');
            s.push('\'');
        }
        LitKind::Real(text) => s.push_str(text),
        LitKind::Bool(b) => s.push_str(if *b { "TRUE" } else { "FALSE" }),
        LitKind::String(bytes) => {
            s.push('"');
            for &b in bytes {
                escape(s, b, b'"');
            }
            s.push('"');
        }
    }
    if let Some(t) = &lit.ty {
        s.push('(');
        write_ty(s, t);
        s.push(')');
    }
}

fn escape(s: &mut String, b: u8, quote: u8) {
    match b {
        b'*' => s.push_str("**"),
        b'\n' => s.push_str("*n"),
        b'\r' => s.push_str("*c"),
        b'\t' => s.push_str("*t"),
        _ if b == quote => {
            s.push('*');
            s.push(b as char);
        }
        b' '..=b'~' => s.push(b as char),
        _ => {
            let _ = write!(s, "*#{b:02X}");
        }
    }
}

/// The first line of an extended input: `c ?? x; y` or `c ?? CASE tag; x`.
fn extended_s(input: &Process) -> String {
    match &input.kind {
        ProcessKind::Input { chan, items } => format!("{} ?? {}", expr(chan), items_s(items)),
        ProcessKind::CaseInput { chan, variants } => {
            let mut text = format!("{} ?? CASE", expr(chan));
            if let [v] = variants.as_slice() {
                let _ = write!(text, " {}", v.tag.text);
                for item in &v.items {
                    let _ = write!(text, "; {}", item_s(item));
                }
            }
            text
        }
        _ => "SKIP".to_string(),
    }
}
