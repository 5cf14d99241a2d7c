//! `ASM` blocks in the subset that runs on this machine (see [`AsmOp`]): straight-line code
//! over the evaluation stack, with integer constants and INT variables as operands. Blocks
//! outside the subset (other instructions, `ADDRESSOF`, labels, `GUY`) are left unrecorded and
//! the code generator reports them.

use occ_grammar::ast::{self, Span};

use super::Checker;
use crate::checked::{AsmOp, SymbolKind};
use crate::types::{Prim, Type};

impl Checker {
    /// Records `block` as [`AsmOp`]s when every line is in the subset.
    pub(super) fn asm(&mut self, block: &ast::AsmBlock, span: Span) {
        if block.guy {
            return;
        }
        let mut ops = Vec::new();
        for line in &block.lines {
            let line = line.split("--").next().unwrap_or_default().trim();
            if line.is_empty() {
                continue;
            }
            let (code, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
            let operands: Vec<&str> = if rest.trim().is_empty() {
                Vec::new()
            } else {
                rest.split(',').map(str::trim).collect()
            };
            let Some(mut line_ops) = self.asm_line(&code.to_ascii_uppercase(), &operands) else {
                return;
            };
            ops.append(&mut line_ops);
        }
        if self.shadow == 0 {
            self.out.asm.insert(span, ops);
        }
    }

    /// One instruction as ops, or `None` when it is outside the subset.
    fn asm_line(&mut self, code: &str, operands: &[&str]) -> Option<Vec<AsmOp>> {
        let loads = |c: &mut Checker| -> Option<Vec<AsmOp>> {
            operands.iter().rev().map(|o| c.asm_load(o)).collect()
        };
        let stores = |c: &mut Checker| -> Option<Vec<AsmOp>> {
            operands.iter().map(|o| c.asm_store(o)).collect()
        };
        match (code, operands.len()) {
            ("LDC", 1) => Some(vec![AsmOp::Const(asm_number(operands[0])?)]),
            ("LD", 1) | ("LDAB", 2) | ("LDABC", 3) => loads(self),
            ("ST", 1) | ("STAB", 2) | ("STABC", 3) => stores(self),
            ("POP", 0) => Some(vec![AsmOp::Pop]),
            ("REV", 0) => Some(vec![AsmOp::Rev]),
            _ => None,
        }
    }

    fn asm_load(&mut self, operand: &str) -> Option<AsmOp> {
        match asm_number(operand) {
            Some(n) => Some(AsmOp::Const(n)),
            None => self.asm_variable(operand, false).map(AsmOp::Load),
        }
    }

    fn asm_store(&mut self, operand: &str) -> Option<AsmOp> {
        self.asm_variable(operand, true).map(AsmOp::Store)
    }

    /// An operand naming an INT variable in scope (assignable when `store`).
    fn asm_variable(&mut self, operand: &str, store: bool) -> Option<crate::checked::SymbolId> {
        let ok_name = !operand.is_empty()
            && operand
                .chars()
                .next()
                .is_some_and(|c| c.is_ascii_alphabetic())
            && operand
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '.' || c == '_');
        if !ok_name {
            return None;
        }
        let id = self.scope.lookup(operand)?;
        let sym = self.sym(id);
        let variable = matches!(
            sym.kind,
            SymbolKind::Variable | SymbolKind::Abbrev { .. } | SymbolKind::Param { .. }
        ) || (!store && matches!(sym.kind, SymbolKind::Val { .. }));
        let word = matches!(self.out.types.underlying(&sym.ty), Type::Prim(Prim::Int));
        (variable && word && (!store || sym.assignable)).then_some(id)
    }
}

/// An integer literal operand: decimal or `#` hexadecimal, optionally negative.
fn asm_number(operand: &str) -> Option<i64> {
    let (neg, digits) = match operand.strip_prefix('-') {
        Some(d) => (true, d.trim()),
        None => (false, operand),
    };
    let n = match digits.strip_prefix('#') {
        Some(hex) => i64::from_str_radix(hex, 16).ok()?,
        None => digits.parse::<i64>().ok()?,
    };
    let n = if neg { -n } else { n };
    i32::try_from(n).ok().map(i64::from).or_else(|| {
        // `#FFFFFFFF` and the like: a word's bit pattern.
        u32::try_from(n).ok().map(|u| i64::from(u as i32))
    })
}
