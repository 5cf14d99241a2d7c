//! Array constructors `[i = base FOR count STEP s | value]` with a constant count: the elements
//! are evaluated in index order into a temporary in the frame.

use cranelift_codegen::ir::condcodes::IntCC;
use cranelift_codegen::ir::{InstBuilder, types};
use occ_compiler::types::Type;
use occ_grammar::ast::{Expr, Replicator};

use super::{Loc, Res, Storage, Tr, mem};
use crate::layout::size_of;

impl Tr<'_, '_> {
    /// Evaluates an array constructor of type `ty` (whose count the checker found constant)
    /// into a frame temporary. The loop has no timeslice poll: its trip count is a constant.
    pub fn constructor(&mut self, r: &Replicator, value: &Expr, ty: Type, e: &Expr) -> Res<Loc> {
        let Type::Array(Some(n), elem) = &ty else {
            return Err(self
                .cx
                .unsupported(e.span, "an array constructor whose count is not constant"));
        };
        let (n, elem) = (*n, (**elem).clone());
        let es = size_of(&self.cx.checked.types, &elem)
            .ok_or_else(|| self.cx.unsupported(e.span, "a constructor of open arrays"))?;
        let off = self.frame.alloc(es * i64::from(n).max(1));
        let idx_off = self.frame.alloc_word();
        let base = self.expr(&r.base)?;
        let step = match &r.step {
            Some(s) => self.expr(s)?,
            None => self.b.ins().iconst(types::I32, 1),
        };
        let sym = self.cx.symbol(&r.name)?;
        let depth = self.depth;
        self.cx.env.insert(
            sym,
            Storage::Var {
                depth,
                offset: idx_off,
            },
        );
        let ia = self.local_addr(idx_off);
        self.store_scalar(base, ia);
        let (head, body, exit) = (
            self.b.create_block(),
            self.b.create_block(),
            self.b.create_block(),
        );
        self.b.append_block_param(head, types::I64);
        let zero = self.b.ins().iconst(types::I64, 0);
        self.b.ins().jump(head, &[zero.into()]);
        self.b.switch_to_block(head);
        let k = self.b.block_params(head)[0];
        let more = self
            .b
            .ins()
            .icmp_imm_s(IntCC::SignedLessThan, k, i64::from(n));
        self.b.ins().brif(more, body, &[], exit, &[]);
        self.b.switch_to_block(body);
        let at = self.local_addr(off);
        let rel = self.b.ins().imul_imm_s(k, es);
        let at = self.b.ins().iadd(at, rel);
        self.assign_to(at, &elem, &[], value)?;
        let ia = self.local_addr(idx_off);
        let i = self.b.ins().load(types::I32, mem(), ia, 0);
        let i = self.b.ins().iadd(i, step);
        self.b.ins().store(mem(), i, ia, 0);
        let k1 = self.b.ins().iadd_imm_s(k, 1);
        self.b.ins().jump(head, &[k1.into()]);
        self.b.switch_to_block(exit);
        let mut dims = vec![self.iconst(i64::from(n))];
        for d in crate::layout::static_dims(&elem) {
            dims.push(self.iconst(i64::from(d.unwrap_or(0))));
        }
        let addr = self.local_addr(off);
        Ok(Loc { addr, ty, dims })
    }
}
