//! `ASM` and `GUY` blocks: transputer instructions over the evaluation stack (see
//! [`AsmCode`] for the address model). Each line is read here from the raw text the layout
//! pass kept: the instruction, then operands that are occam expressions (parsed with the
//! grammar's expression parser and checked with the expression rules), labels (`:name`) or
//! workspace slots. `GUY` blocks take the same instructions (`LDL x` loads the variable `x`,
//! `LDLP x` is its address, as occ21 did).

use occ_grammar::ast::{self, Expr, Span};

use super::Checker;
use super::place::is_element;
use crate::checked::{AsmCode, AsmOp, SymbolKind};
use crate::consteval::Value;
use crate::diagnostic::DiagnosticKind;
use crate::types::{Prim, Type};
use crate::usage::Mode;

/// The furthest a block's workspace slots (and `RESERVELOWWS`) may reach from its Wptr, in
/// words: a frame keeps room for all of them.
const MAX_SLOTS: u32 = 1 << 16;

/// One character of a block's text with its offset in the program text and its line.
#[derive(Clone, Copy)]
struct Char {
    at: usize,
    line: usize,
    line_start: usize,
    c: char,
}

/// One instruction line (or label), with the operands split at top-level commas.
struct Instr {
    /// The instruction, upper case; empty for a label.
    code: String,
    /// For a label, its name; otherwise the operands.
    operands: Vec<Vec<Char>>,
    /// The line's span.
    span: Span,
}

/// A workspace slot before the named slots get their numbers.
#[derive(Clone, Copy)]
enum SlotBase {
    Number(i64),
    Static,
    VsPtr,
    WsSize,
}

/// An instruction on a workspace slot, with the `AJW` displacement in force
/// (`ws` times `.WSSIZE` plus `n`).
#[derive(Clone, Copy)]
struct Slot {
    kind: SlotKind,
    base: SlotBase,
    ajw_ws: i64,
    ajw_n: i64,
}

#[derive(Clone, Copy)]
enum SlotKind {
    Load,
    Store,
    Address,
}

enum Pending {
    Op(AsmOp),
    Slot(Slot),
}

/// The state of one block's check.
#[derive(Default)]
struct Block {
    /// The block's labels, with their offsets in the program's code image.
    labels: Vec<(String, usize)>,
    /// Where the block's `BYTE` and `WORD` bytes start in the program's code image.
    base: usize,
    image: Vec<u8>,
    /// Where each `LDPI`'s next instruction lies in the code image, in order, and how many of
    /// them the second pass has used.
    ldpi: Vec<usize>,
    ldpi_used: usize,
    reserve: u32,
    ajw_ws: i64,
    ajw_n: i64,
    /// The span of the line being checked.
    span: Span,
    ops: Vec<(Pending, Span)>,
}

impl Checker {
    /// Checks `block` and records its [`AsmCode`]; reports every line occ cannot run.
    pub(super) fn asm(&mut self, block: &ast::AsmBlock, span: Span) {
        let instrs = split_lines(block, span);
        let mut b = Block {
            base: self.out.asm_image.len(),
            ..Block::default()
        };
        let mut ok = self.asm_layout(&instrs, &mut b);
        for i in &instrs {
            ok &= self.asm_instr(i, &mut b).is_some();
        }
        if ok && self.shadow == 0 {
            let code = finish(&mut b);
            if code.low_words.max(code.high_words) > MAX_SLOTS {
                let what = format!("the block's workspace slots reach beyond {MAX_SLOTS} words");
                self.asm_error(what, span);
                return;
            }
            self.asm_labels.extend(b.labels.iter().cloned());
            self.out.asm_image.append(&mut b.image);
            self.out.asm.insert(span, code);
        }
    }

    /// The first pass: label numbers, and the code image of `BYTE` and `WORD` lines (label
    /// positions are offsets in it).
    fn asm_layout(&mut self, instrs: &[Instr], b: &mut Block) -> bool {
        let mut ok = true;
        for i in instrs {
            match i.code.as_str() {
                "" => {
                    let name = text(&i.operands[0]);
                    if name.is_empty() || name.contains(char::is_whitespace) {
                        ok &= self.asm_error("a label is `:` and a name".into(), i.span);
                    }
                    if b.labels.iter().any(|(n, _)| *n == name) {
                        ok &=
                            self.asm_error(format!("the label `:{name}` is defined twice"), i.span);
                    }
                    b.labels.push((name, b.base + b.image.len()));
                }
                "LDPI" => b.ldpi.push(b.base + b.image.len()),
                "BYTE" | "WORD" => {
                    for o in &i.operands {
                        match self.asm_data(o, i.code == "WORD") {
                            Some(mut bytes) => b.image.append(&mut bytes),
                            None => ok = false,
                        }
                    }
                }
                _ => {}
            }
        }
        ok
    }

    /// The bytes of one `BYTE` operand (a byte, a string or a table of bytes) or `WORD`
    /// operand (a 32-bit word, little-endian).
    fn asm_data(&mut self, o: &[Char], word: bool) -> Option<Vec<u8>> {
        let e = self.asm_expr(o)?;
        let t = self.expr(&e, None);
        let bad = || format!("`{}` is not a constant byte, string or word", text(o));
        let Some(v) = t.value else {
            self.asm_error(bad(), e.span);
            return None;
        };
        let mut out = Vec::new();
        let values = match v {
            Value::Array(vs) => vs,
            v => vec![v],
        };
        for v in values {
            let n = match v {
                Value::Int(n) => n,
                Value::Bool(b) => i64::from(b),
                _ => {
                    self.asm_error(bad(), e.span);
                    return None;
                }
            };
            let fits = if word {
                i32::try_from(n).is_ok() || u32::try_from(n).is_ok()
            } else {
                u8::try_from(n).is_ok()
            };
            if !fits {
                let what = if word { "a word" } else { "a byte" };
                self.asm_error(format!("`{}`: {n} does not fit {what}", text(o)), e.span);
                return None;
            }
            if word {
                out.extend_from_slice(&(n as u32).to_le_bytes());
            } else {
                out.extend_from_slice(&n.to_le_bytes()[..1]);
            }
        }
        Some(out)
    }

    fn asm_error(&mut self, what: String, span: Span) -> bool {
        self.error(DiagnosticKind::Asm { what }, span);
        false
    }

    /// Checks one instruction and appends its ops.
    fn asm_instr(&mut self, i: &Instr, b: &mut Block) -> Option<()> {
        b.span = i.span;
        let code = i.code.as_str();
        let ops = &i.operands;
        let count = |n: usize| ops.len() == n;
        // The workspace displacement is counted in text order, so control cannot meet or leave
        // a point where AJW has moved it.
        let joins = matches!(code, "" | "J" | "CJ");
        if joins && (b.ajw_ws != 0 || b.ajw_n != 0) {
            self.asm_error(
                "a label, J or CJ where AJW has moved the workspace (move it back first)".into(),
                i.span,
            );
            return None;
        }
        match code {
            "" => {
                let name = text(&ops[0]);
                let at = b.labels.iter().position(|(n, _)| *n == name)?;
                b.push_op(AsmOp::Label(at));
            }
            "BYTE" | "WORD" => {}
            "LD" | "LDAB" | "LDABC" if operand_count(code) == Some(ops.len()) => {
                for o in ops.iter().rev() {
                    let op = self.asm_load(o)?;
                    b.push_op(op);
                }
            }
            "ST" | "STAB" | "STABC" if operand_count(code) == Some(ops.len()) => {
                for o in ops {
                    let e = self.asm_expr(o)?;
                    let op = self.asm_store(&e)?;
                    b.push_op(op);
                }
            }
            "LDC" if count(1) => {
                let n = self.asm_constant(&ops[0])?;
                b.push_op(AsmOp::Const(n));
            }
            "LDL" | "STL" | "LDLP" if count(1) => self.asm_slot(code, &ops[0], b)?,
            "AJW" if count(1) => {
                let t = text(&ops[0]).replace(' ', "");
                match t.as_str() {
                    ".WSSIZE" => b.ajw_ws += 1,
                    "-.WSSIZE" => b.ajw_ws -= 1,
                    _ => b.ajw_n += self.asm_constant(&ops[0])?,
                }
            }
            "RESERVELOWWS" if count(1) => {
                let n = self.asm_constant(&ops[0])?;
                let Ok(n) = u32::try_from(n) else {
                    self.asm_error("RESERVELOWWS needs a count of words".into(), i.span);
                    return None;
                };
                b.reserve = b.reserve.max(n);
            }
            "J" | "CJ" if count(1) => {
                let at = self.asm_label(&ops[0], b)?;
                let op = if code == "J" {
                    AsmOp::Jump(at)
                } else {
                    AsmOp::CondJump(at)
                };
                b.push_op(op);
            }
            "LDLABELDIFF" if count(1) => {
                let n = self.asm_label_diff(&ops[0], b)?;
                b.push_op(AsmOp::Const(n));
            }
            "LDPI" if count(0) => {
                let at = b.ldpi.get(b.ldpi_used).copied()?;
                b.ldpi_used += 1;
                b.push_op(AsmOp::Ldpi(at as i64));
            }
            "LB" if count(0) => b.push_op(AsmOp::Lb),
            "WSUB" if count(0) => b.push_op(AsmOp::Wsub),
            "POP" if count(0) => b.push_op(AsmOp::Pop),
            "REV" if count(0) => b.push_op(AsmOp::Rev),
            "OUTWORD" if count(0) && self.valof_depth > 0 => {
                self.asm_error(
                    "OUTWORD cannot be used inside a VALOF (no side effects)".into(),
                    i.span,
                );
                return None;
            }
            "OUTWORD" if count(0) => {
                b.push_op(AsmOp::Outword);
            }
            "ADC" if count(1) && !self.asm_is_constant(&ops[0]) => {
                let e = self.asm_expr(&ops[0])?;
                match self.asm_value(&e)? {
                    AsmOp::Load(e) => b.push_op(AsmOp::AdcValue(e)),
                    AsmOp::Const(n) => b.push_op(AsmOp::Adc(n)),
                    _ => return None,
                }
            }
            "ADC" | "LDNL" | "STNL" if count(1) => {
                let n = self.asm_constant(&ops[0])?;
                b.push_op(match code {
                    "ADC" => AsmOp::Adc(n),
                    "LDNL" => AsmOp::Ldnl(n),
                    _ => AsmOp::Stnl(n),
                });
            }
            "PFIX" if count(1) => {
                if self.asm_constant(&ops[0])? != 0 {
                    self.asm_error(
                        "only `PFIX 0` is supported (a prefix of nothing)".into(),
                        i.span,
                    );
                    return None;
                }
            }
            "CALL" if count(1) => self.asm_call(&ops[0], b)?,
            _ if operand_count(code).is_some() => {
                let n = operand_count(code).unwrap_or_default();
                let found = ops.len();
                self.asm_error(
                    format!("`{code}` takes {n} operand(s), found {found}"),
                    i.span,
                );
                return None;
            }
            _ => {
                self.asm_error(
                    format!("`{code}` is not a transputer instruction occ runs in ASM"),
                    i.span,
                );
                return None;
            }
        }
        Some(())
    }

    /// Parses an operand as an expression: its lines go to the parser at their own offsets
    /// (the first padded to the operand's column), so that spans point into the program.
    fn asm_expr(&mut self, o: &[Char]) -> Option<Expr> {
        let mut lines: Vec<(usize, String)> = Vec::new();
        let mut last_line = usize::MAX;
        for ch in o {
            if ch.line != last_line {
                let pad = ch.at.saturating_sub(ch.line_start);
                lines.push((ch.line_start, " ".repeat(pad)));
                last_line = ch.line;
            }
            if let Some(l) = lines.last_mut() {
                l.1.push(ch.c);
            }
        }
        let refs: Vec<(usize, &str)> = lines.iter().map(|(a, s)| (*a, s.as_str())).collect();
        match occ_grammar::parser::parse_expression(&refs) {
            Ok(e) => Some(e),
            Err(diags) => {
                let what = diags
                    .first()
                    .map_or_else(|| "not an expression".to_string(), |d| d.message.clone());
                // The parser sees the operand inside an abbreviation (`VAL x IS ... :`): its end
                // reached early is that wrapper's `:` or the end of the text.
                let written = text(o);
                let early = (what.contains("`:`") && !written.contains(':'))
                    || what.contains("end of line")
                    || what.contains("end of input");
                let what = if early {
                    "the expression ends early (an operator, a bracket or a quote is left open)"
                        .to_string()
                } else {
                    what
                };
                self.asm_error(format!("operand `{written}`: {what}"), span_of(o));
                None
            }
        }
    }

    /// Whether an operand is a constant, without reporting anything (a name of a variable or
    /// an expression over variables is not).
    fn asm_is_constant(&mut self, o: &[Char]) -> bool {
        let t = text(o);
        !t.split(|c: char| !(c.is_ascii_alphanumeric() || c == '.'))
            .filter(|w| w.chars().next().is_some_and(|c| c.is_ascii_alphabetic()))
            .any(|w| {
                self.scope.lookup(w).is_some_and(|id| {
                    !matches!(
                        self.sym(id).kind,
                        SymbolKind::Val { value: Some(_) } | SymbolKind::Predefined(_)
                    )
                })
            })
    }

    /// An operand that must be an INT constant.
    fn asm_constant(&mut self, o: &[Char]) -> Option<i64> {
        let e = self.asm_expr(o)?;
        let t = self.expr(&e, Some(&Type::Prim(Prim::Int)));
        match t.value.as_ref().and_then(Value::as_int) {
            Some(n) if i32::try_from(n).is_ok() => Some(n),
            Some(n) => {
                self.asm_error(format!("{n} does not fit a 32-bit word"), e.span);
                None
            }
            None => {
                self.asm_error(format!("`{}` is not an INT constant", text(o)), e.span);
                None
            }
        }
    }

    /// The op pushing an operand of `LD`: `ADDRESSOF x`, a constant or any expression of a
    /// primitive type, or a channel (its address).
    fn asm_load(&mut self, o: &[Char]) -> Option<AsmOp> {
        if let Some(rest) = strip_word(o, "ADDRESSOF") {
            return self.asm_address(rest);
        }
        let e = self.asm_expr(o)?;
        self.asm_value(&e)
    }

    fn asm_value(&mut self, e: &Expr) -> Option<AsmOp> {
        if is_element(e) {
            let p = self.place(e, None);
            let chan = matches!(self.out.types.underlying(&p.ty), Type::Chan(..));
            if !chan && let Some(t) = &p.target {
                self.record(t.symbol, Mode::Read, t.part, t.span);
            }
            if let Some(n) = p.value.as_ref().and_then(Value::as_int)
                && word_sized(&self.out.types.underlying(&p.ty).clone())
            {
                return Some(AsmOp::Const(n));
            }
            return self
                .asm_operand_type(&p.ty, e)
                .then(|| AsmOp::Load(e.clone()));
        }
        let t = self.expr(e, None);
        if let Some(n) = t.value.as_ref().and_then(Value::as_int)
            && word_sized(&self.out.types.underlying(&t.ty).clone())
        {
            return Some(AsmOp::Const(n));
        }
        let prim = matches!(self.out.types.underlying(&t.ty), Type::Prim(_));
        if !prim {
            self.asm_error(
                "an ASM operand must be a value of a primitive type".into(),
                e.span,
            );
            return None;
        }
        Some(AsmOp::Load(e.clone()))
    }

    /// Reports whether an element of type `ty` can be an ASM operand.
    fn asm_operand_type(&mut self, ty: &Type, e: &Expr) -> bool {
        let ok = matches!(
            self.out.types.underlying(ty),
            Type::Prim(_) | Type::Chan(..) | Type::Error
        );
        if !ok {
            self.asm_error(
                "an ASM operand must be a variable of a primitive type or a channel".into(),
                e.span,
            );
        }
        ok
    }

    /// `ADDRESSOF x`: an element, a constant, a table, a string or a PROC.
    fn asm_address(&mut self, o: &[Char]) -> Option<AsmOp> {
        let e = self.asm_expr(o)?;
        if let ast::ExprKind::Name(n) = &e.kind
            && let Some(id) = self.scope.lookup(&n.text)
            && matches!(self.sym(id).kind, SymbolKind::Proc(_))
        {
            self.lookup(n);
            return Some(AsmOp::ProcAddress(id));
        }
        if is_element(&e) {
            let p = self.place(&e, None);
            let chan = matches!(self.out.types.underlying(&p.ty), Type::Chan(..));
            if !chan && let Some(t) = &p.target {
                self.record(t.symbol, Mode::Read, t.part, t.span);
            }
            return Some(AsmOp::Address(e));
        }
        let t = self.expr(&e, None);
        if t.value.is_none() && !matches!(t.ty, Type::Error) {
            self.asm_error(
                "ADDRESSOF needs a variable, a constant, a table or a PROC".into(),
                e.span,
            );
            return None;
        }
        Some(AsmOp::Address(e))
    }

    /// The op storing A in element `e`.
    fn asm_store(&mut self, e: &Expr) -> Option<AsmOp> {
        if !is_element(e) {
            self.asm_error("ST needs a variable".into(), e.span);
            return None;
        }
        let p = self.place(e, None);
        if !p.assignable {
            let name = super::process::element_name(e);
            self.error(DiagnosticKind::NotAssignable { name }, e.span);
            return None;
        }
        if matches!(self.out.types.underlying(&p.ty), Type::Chan(..)) {
            self.asm_error("ST cannot store into a channel".into(), e.span);
            return None;
        }
        if !self.asm_operand_type(&p.ty, e) {
            return None;
        }
        if let Some(t) = &p.target {
            self.record(t.symbol, Mode::Write, t.part, t.span);
        }
        Some(AsmOp::Store(e.clone()))
    }

    /// `LDL`, `STL` and `LDLP`: a numbered or named workspace slot, or a variable.
    fn asm_slot(&mut self, code: &str, o: &[Char], b: &mut Block) -> Option<()> {
        let kind = match code {
            "LDL" => SlotKind::Load,
            "STL" => SlotKind::Store,
            _ => SlotKind::Address,
        };
        let t = text(o);
        let base = match t.as_str() {
            ".STATIC" => Some(SlotBase::Static),
            ".VSPTR" => Some(SlotBase::VsPtr),
            ".WSSIZE" => Some(SlotBase::WsSize),
            _ => None,
        };
        let base = match base {
            Some(b) => b,
            None => {
                let e = self.asm_expr(o)?;
                let named = matches!(&e.kind, ast::ExprKind::Name(n)
                    if self.scope.lookup(&n.text).is_some_and(|id| !matches!(
                        self.sym(id).kind, SymbolKind::Val { value: Some(_) })));
                if named || is_element(&e) && !matches!(e.kind, ast::ExprKind::Name(_)) {
                    let op = match kind {
                        SlotKind::Load => self.asm_value(&e)?,
                        SlotKind::Store => self.asm_store(&e)?,
                        SlotKind::Address => self.asm_address(o)?,
                    };
                    b.push_op(op);
                    return Some(());
                }
                SlotBase::Number(self.asm_constant(o)?)
            }
        };
        let slot = Slot {
            kind,
            base,
            ajw_ws: b.ajw_ws,
            ajw_n: b.ajw_n,
        };
        b.ops.push((Pending::Slot(slot), b.span));
        Some(())
    }

    /// A `:label` operand: its number.
    fn asm_label(&mut self, o: &[Char], b: &Block) -> Option<usize> {
        let t = text(o);
        let span = span_of(o);
        let Some(name) = t.strip_prefix(':') else {
            self.asm_error(format!("`{t}` is not a label (`:name`)"), span);
            return None;
        };
        let name = name.trim();
        let found = b.labels.iter().position(|(n, _)| n == name);
        if found.is_none() {
            self.asm_error(
                format!("the label `:{name}` is not defined in this block"),
                span,
            );
        }
        found
    }

    /// `LDLABELDIFF :a - :b`: the distance in the code image from `b` to `a`.
    fn asm_label_diff(&mut self, o: &[Char], b: &Block) -> Option<i64> {
        let t = text(o);
        let parts: Vec<&str> = t.splitn(2, " - ").collect();
        let [a, c] = parts.as_slice() else {
            self.asm_error(format!("`{t}` is not `:label - :label`"), span_of(o));
            return None;
        };
        let (a, c) = (a.trim().to_string(), c.trim().to_string());
        // A label of this block, or of the latest earlier block that defines it.
        let earlier = &self.asm_labels;
        let at = |name: &str| -> Option<usize> {
            let name = name.strip_prefix(':')?.trim();
            let mine = b.labels.iter().find(|(n, _)| n == name);
            let theirs = || earlier.iter().rev().find(|(n, _)| n == name);
            mine.or_else(theirs).map(|(_, p)| *p)
        };
        match (at(&a), at(&c)) {
            (Some(x), Some(y)) => Some(x as i64 - y as i64),
            _ => {
                self.asm_error(
                    format!("`{t}` names a label not defined in this block or an earlier one"),
                    span_of(o),
                );
                None
            }
        }
    }

    /// `CALL name`: a PROC or FUNCTION whose parameters come from the stack.
    fn asm_call(&mut self, o: &[Char], b: &mut Block) -> Option<()> {
        let t = text(o);
        let span = span_of(o);
        let name = ast::Name {
            text: t.clone(),
            span,
        };
        let id = self.lookup(&name)?;
        let (pid, function) = match self.sym(id).kind {
            SymbolKind::Proc(p) => (p, false),
            SymbolKind::Function(p) => (p, true),
            _ => {
                self.asm_error(format!("`{t}` is not a PROC or FUNCTION"), span);
                return None;
            }
        };
        let info = &self.out.procs[pid];
        let params = info.params.clone();
        let results = info.results.len();
        let scalar = params.iter().all(|p| {
            let ty = &self.out.symbols[*p].ty;
            matches!(self.out.types.underlying(ty), Type::Prim(_))
        });
        if params.len() > 3 || !scalar || (function && results != 1) {
            self.asm_error(
                format!(
                    "CALL `{t}`: only a PROC or FUNCTION of at most three parameters of \
                     primitive types (and one result) can take them from the stack"
                ),
                span,
            );
            return None;
        }
        if !function && self.valof_depth > 0 {
            self.asm_error(
                format!("CALL `{t}`: a PROC cannot be called inside a VALOF (no side effects)"),
                span,
            );
            return None;
        }
        // What the callee does to variables declared outside it, as an ordinary call records.
        self.free_variables_of(pid, span);
        let op = if function {
            AsmOp::CallFunction(id)
        } else {
            // occ21 passes a static link, in A, to a PROC that uses variables declared outside
            // it (a nested PROC's free variables); occ supplies its own and drops that one.
            let first = params.first().copied();
            let skip_link = self.out.procs[pid]
                .usage
                .iter()
                .any(|a| first.is_none_or(|p| a.symbol < p));
            AsmOp::CallProc { sym: id, skip_link }
        };
        b.push_op(op);
        Some(())
    }
}

/// The instructions occ runs, with their operand counts (`BYTE` and `WORD` take any number).
const INSTRUCTIONS: [(&str, usize); 26] = [
    ("LD", 1),
    ("LDAB", 2),
    ("LDABC", 3),
    ("ST", 1),
    ("STAB", 2),
    ("STABC", 3),
    ("LDC", 1),
    ("LDL", 1),
    ("STL", 1),
    ("LDLP", 1),
    ("AJW", 1),
    ("RESERVELOWWS", 1),
    ("J", 1),
    ("CJ", 1),
    ("LDLABELDIFF", 1),
    ("LDPI", 0),
    ("LB", 0),
    ("WSUB", 0),
    ("POP", 0),
    ("REV", 0),
    ("OUTWORD", 0),
    ("ADC", 1),
    ("LDNL", 1),
    ("STNL", 1),
    ("PFIX", 1),
    ("CALL", 1),
];

/// The operand count of an instruction occ runs, `None` for one it does not.
fn operand_count(code: &str) -> Option<usize> {
    INSTRUCTIONS
        .iter()
        .find(|(c, _)| *c == code)
        .map(|(_, n)| *n)
}

/// Whether a constant of `ty` fits one 32-bit word (pushed as a constant).
fn word_sized(ty: &Type) -> bool {
    matches!(
        ty,
        Type::Prim(Prim::Int | Prim::Int32 | Prim::Int16 | Prim::Byte | Prim::Bool)
    )
}

impl Block {
    /// Appends `op`, at the line being checked.
    fn push_op(&mut self, op: AsmOp) {
        self.ops.push((Pending::Op(op), self.span));
    }
}

/// Numbers the named slots after the numbered ones and sizes the block's workspace area.
fn finish(b: &mut Block) -> AsmCode {
    let numbered = b
        .ops
        .iter()
        .filter_map(|p| match p {
            (
                Pending::Slot(Slot {
                    base: SlotBase::Number(n),
                    ..
                }),
                _,
            ) if *n >= 0 => Some(*n + 1),
            _ => None,
        })
        .max()
        .unwrap_or(0);
    let ws_size = numbered + 2;
    let (mut low, mut high) = (i64::from(b.reserve), 0i64);
    let (pending, spans): (Vec<Pending>, Vec<Span>) =
        std::mem::take(&mut b.ops).into_iter().unzip();
    let ops = pending
        .into_iter()
        .map(|p| match p {
            Pending::Op(op) => op,
            Pending::Slot(s) => {
                let base = match s.base {
                    SlotBase::Number(n) => n,
                    SlotBase::Static => numbered,
                    SlotBase::VsPtr => numbered + 1,
                    SlotBase::WsSize => ws_size,
                };
                let n = base + s.ajw_ws * ws_size + s.ajw_n;
                low = low.max(-n);
                high = high.max(n + 1);
                match s.kind {
                    SlotKind::Load => AsmOp::LoadSlot(n),
                    SlotKind::Store => AsmOp::StoreSlot(n),
                    SlotKind::Address => AsmOp::SlotAddress(n),
                }
            }
        })
        .collect();
    AsmCode {
        ops,
        spans,
        low_words: u32::try_from(low).unwrap_or(u32::MAX),
        high_words: u32::try_from(high).unwrap_or(u32::MAX),
    }
}

/// The text of characters, trimmed.
/// An operand's text as written, its lines joined by a space.
fn text(o: &[Char]) -> String {
    let mut out = String::new();
    for (k, c) in o.iter().enumerate() {
        if k > 0 && o[k - 1].line != c.line {
            out.push(' ');
        }
        out.push(c.c);
    }
    out.trim().to_string()
}

fn span_of(o: &[Char]) -> Span {
    match (o.first(), o.last()) {
        (Some(a), Some(z)) => Span::new(a.at, z.at + z.c.len_utf8()),
        _ => Span::new(0, 0),
    }
}

/// The characters after a leading keyword `word` (and the spaces after it).
fn strip_word<'a>(o: &'a [Char], word: &str) -> Option<&'a [Char]> {
    let head: String = o.iter().take(word.len()).map(|c| c.c).collect();
    let next = o.get(word.len()).map(|c| c.c);
    if head != word || !next.is_some_and(char::is_whitespace) {
        return None;
    }
    let rest = o.get(word.len()..)?;
    let skip = rest.iter().take_while(|c| c.c.is_whitespace()).count();
    rest.get(skip..)
}

/// Splits a block into instructions: comments removed, a line whose brackets are still open
/// continued on the next, operands split at top-level commas and trimmed.
fn split_lines(block: &ast::AsmBlock, span: Span) -> Vec<Instr> {
    let mut out = Vec::new();
    let mut pending: Vec<Char> = Vec::new();
    let mut depth = 0i32;
    for (li, line) in block.lines.iter().enumerate() {
        let start = block.line_spans.get(li).map_or(span.start, |s| s.start);
        let mut quote: Option<char> = None;
        let chars: Vec<(usize, char)> = line.char_indices().collect();
        let mut k = 0;
        while let Some(&(i, c)) = chars.get(k) {
            match quote {
                Some(q) => {
                    if c == '*' {
                        pending.push(Char {
                            at: start + i,
                            line: li,
                            line_start: start,
                            c,
                        });
                        k += 1;
                        if let Some(&(j, d)) = chars.get(k) {
                            pending.push(Char {
                                at: start + j,
                                line: li,
                                line_start: start,
                                c: d,
                            });
                        }
                        k += 1;
                        continue;
                    }
                    if c == q {
                        quote = None;
                    }
                }
                None => match c {
                    '-' if chars.get(k + 1).is_some_and(|&(_, d)| d == '-') => break,
                    '"' | '\'' => quote = Some(c),
                    '(' | '[' => depth += 1,
                    ')' | ']' => depth -= 1,
                    _ => {}
                },
            }
            pending.push(Char {
                at: start + i,
                line: li,
                line_start: start,
                c,
            });
            k += 1;
        }
        if depth > 0 || continues(&pending) {
            continue;
        }
        depth = 0;
        if pending.iter().all(|c| c.c.is_whitespace()) {
            pending.clear();
            continue;
        }
        out.push(instr(std::mem::take(&mut pending)));
    }
    if !pending.iter().all(|c| c.c.is_whitespace()) {
        out.push(instr(pending));
    }
    out
}

/// Whether an instruction line goes on to the next line, as an occam line does: after a comma
/// or an operator (`AND`, `OR` and the symbols, except the `-` of `AJW -` before `.WSSIZE`).
fn continues(pending: &[Char]) -> bool {
    let text: String = pending.iter().map(|c| c.c).collect();
    let text = text.trim_end();
    let words: Vec<&str> = text.split_whitespace().collect();
    let ajw_minus = matches!(words.as_slice(), [w, "-"] if w.eq_ignore_ascii_case("AJW"));
    let symbol = text.ends_with([',', '+', '-', '*', '/', '\\', '<', '>', '=', '~']);
    let keyword = words
        .last()
        .is_some_and(|w| ["AND", "OR", "PLUS", "MINUS", "TIMES"].contains(w));
    words.len() > 1 && !ajw_minus && (symbol || keyword)
}

/// One instruction from its characters.
fn instr(chars: Vec<Char>) -> Instr {
    let trimmed: Vec<Char> = {
        let s = chars.iter().position(|c| !c.c.is_whitespace()).unwrap_or(0);
        let e = chars
            .iter()
            .rposition(|c| !c.c.is_whitespace())
            .map_or(0, |e| e + 1);
        chars.get(s..e).unwrap_or_default().to_vec()
    };
    let span = span_of(&trimmed);
    if trimmed.first().is_some_and(|c| c.c == ':') {
        let name = trimmed.get(1..).unwrap_or_default().to_vec();
        return Instr {
            code: String::new(),
            operands: vec![name],
            span,
        };
    }
    let n = trimmed
        .iter()
        .position(|c| c.c.is_whitespace())
        .unwrap_or(trimmed.len());
    let code: String = trimmed
        .iter()
        .take(n)
        .map(|c| c.c.to_ascii_uppercase())
        .collect();
    let rest = trimmed.get(n..).unwrap_or_default();
    Instr {
        code,
        operands: split_operands(rest),
        span,
    }
}

/// Splits at commas outside brackets and quotes; each operand trimmed.
fn split_operands(rest: &[Char]) -> Vec<Vec<Char>> {
    let mut out: Vec<Vec<Char>> = Vec::new();
    let mut cur = Vec::new();
    let (mut depth, mut quote, mut escape) = (0i32, None, false);
    for &c in rest {
        match quote {
            Some(q) => {
                if escape {
                    escape = false;
                } else if c.c == '*' {
                    escape = true;
                } else if c.c == q {
                    quote = None;
                }
            }
            None => match c.c {
                '"' | '\'' => quote = Some(c.c),
                '(' | '[' => depth += 1,
                ')' | ']' => depth -= 1,
                ',' if depth == 0 => {
                    out.push(std::mem::take(&mut cur));
                    continue;
                }
                _ => {}
            },
        }
        cur.push(c);
    }
    out.push(cur);
    out.into_iter()
        .map(|o| {
            let s = o
                .iter()
                .position(|c| !c.c.is_whitespace())
                .unwrap_or(o.len());
            let e = o
                .iter()
                .rposition(|c| !c.c.is_whitespace())
                .map_or(s, |e| e + 1);
            o.get(s..e).unwrap_or_default().to_vec()
        })
        .filter(|o| !o.is_empty())
        .collect()
}
