//! Places (occam's elements): names, subscripts, record fields, slices and non-addressable array
//! values, each as an address with its type and dimension lengths. Subscripts and slices are
//! bounds-checked.

use cranelift_codegen::ir::{InstBuilder, Value, condcodes::IntCC, types};
use occ_compiler::consteval::Value as Const;
use occ_compiler::types::{Type, TypeDefKind};
use occ_grammar::ast::{Expr, ExprKind, Span};
use occ_runtime::ErrorKind;
use occ_runtime::abi::{WORD_BYTES, word_offset};

use super::{Res, Storage, Tr, mem};
use crate::layout::{cl_type, record_fields, size_of, static_dims};

/// An addressable value: its address, type and (for arrays) each dimension's length (`i64`).
#[derive(Clone, Debug)]
pub struct Loc {
    /// Address of the first byte.
    pub addr: Value,
    /// The occam type (array dimensions may be open; `dims` has their lengths).
    pub ty: Type,
    /// Length of each array dimension, outermost first.
    pub dims: Vec<Value>,
}

impl Tr<'_, '_> {
    /// The place `e` denotes (or a temporary holding its value, for array-valued expressions
    /// that are not variables).
    pub fn place(&mut self, e: &Expr) -> Res<Loc> {
        match &e.kind {
            ExprKind::Name(n) => {
                let sym = self.cx.symbol(n)?;
                let ty = self.cx.checked.symbols[sym].ty.clone();
                let ty = match self.cx.checked.expr_types.get(&e.span) {
                    Some(t) if !matches!(t, Type::Error) => t.clone(),
                    _ => ty,
                };
                let st = self.cx.env.get(&sym).cloned().ok_or_else(|| {
                    self.cx
                        .internal(n.span, format!("`{}` has no storage", n.text))
                })?;
                self.storage_loc(&st, ty, e.span)
            }
            ExprKind::Subscript { base, index } => self.subscript(base, index, e.span),
            ExprKind::Slice { base, from, count } => {
                self.slice(base, from.as_deref(), count.as_deref(), e.span)
            }
            ExprKind::Directed { chan, .. } => self.place(chan),
            _ => self.value_loc(e),
        }
    }

    /// The place of a name with storage `st` and type `ty`.
    pub fn storage_loc(&mut self, st: &Storage, ty: Type, span: Span) -> Res<Loc> {
        let ty = crate::layout::resolve(&self.cx.checked.types, &ty);
        let sd = static_dims(&ty);
        match st {
            Storage::Var { depth, offset } => {
                let f = self.frame_at(*depth);
                let addr = self.b.ins().iadd_imm_s(f, i64::from(*offset));
                let dims = sd
                    .iter()
                    .map(|d| self.iconst(i64::from(d.unwrap_or(0))))
                    .collect();
                Ok(Loc { addr, ty, dims })
            }
            Storage::Ref { depth, offset } => {
                let f = self.frame_at(*depth);
                let addr = self.b.ins().load(types::I64, mem(), f, *offset);
                let mut dims = Vec::new();
                for (i, d) in sd.iter().enumerate() {
                    let v = match d {
                        Some(n) => self.iconst(i64::from(*n)),
                        None => self.b.ins().load(
                            types::I64,
                            mem(),
                            f,
                            *offset + word_offset(i as isize + 1),
                        ),
                    };
                    dims.push(v);
                }
                Ok(Loc { addr, ty, dims })
            }
            Storage::Const(c) => {
                let c = c.clone();
                self.const_loc(&c, ty, span)
            }
            Storage::ChanTable { .. } => Err(self.cx.unsupported(
                span,
                "a table of channels used whole (only its elements can be used)",
            )),
            _ => Err(self.cx.internal(span, "a PROC or FUNCTION used as a value")),
        }
    }

    /// A constant placed in memory (read-only program data).
    pub fn const_loc(&mut self, c: &Const, ty: Type, span: Span) -> Res<Loc> {
        let ty = crate::layout::resolve(&self.cx.checked.types, &ty);
        let mut bytes = Vec::new();
        self.encode(c, &ty, &mut bytes, span)?;
        let addr = self.cx.intern(bytes);
        let addr = self.iconst(addr);
        let mut dims = Vec::new();
        let mut cur = Some(c);
        for d in static_dims(&ty) {
            let n = match (d, cur) {
                (Some(n), _) => i64::from(n),
                (None, Some(Const::Array(items))) => items.len() as i64,
                _ => 0,
            };
            dims.push(self.iconst(n));
            cur = match cur {
                Some(Const::Array(items)) => items.first(),
                _ => None,
            };
        }
        Ok(Loc { addr, ty, dims })
    }

    /// Appends the bytes of constant `c` of type `ty`.
    fn encode(&self, c: &Const, ty: &Type, out: &mut Vec<u8>, span: Span) -> Res<()> {
        let table = &self.cx.checked.types;
        match (c, table.underlying(ty)) {
            (Const::Bool(b), _) => out.push(u8::from(*b)),
            (Const::Int(i), Type::Prim(p)) => {
                out.extend_from_slice(&i.to_le_bytes()[..p.bytes() as usize]);
            }
            (Const::Real32(x), _) => out.extend_from_slice(&x.to_le_bytes()),
            (Const::Real64(x), _) => out.extend_from_slice(&x.to_le_bytes()),
            (Const::Array(items), Type::Array(_, e)) => {
                for it in items {
                    self.encode(it, e, out, span)?;
                }
            }
            (Const::Record(vals), Type::Named(_)) => {
                let fields = record_fields(table, ty)
                    .ok_or_else(|| self.cx.internal(span, "record constant"))?;
                let start = out.len();
                let size = size_of(table, ty).unwrap_or(0) as usize;
                out.resize(start + size, 0);
                for (v, (_, off, fty)) in vals.iter().zip(fields) {
                    let mut tmp = Vec::new();
                    self.encode(v, &fty, &mut tmp, span)?;
                    let at = start + off as usize;
                    out[at..at + tmp.len()].copy_from_slice(&tmp);
                }
            }
            _ => return Err(self.cx.internal(span, "constant of unexpected shape")),
        }
        Ok(())
    }

    /// Byte size of one element of array place `l` (dynamic when inner dimensions are open).
    pub fn elem_size(&mut self, l: &Loc, span: Span) -> Res<Value> {
        let elem =
            l.ty.elem()
                .cloned()
                .ok_or_else(|| self.cx.internal(span, "subscript of a non-array"))?;
        self.size_of_loc(&elem, &l.dims[1.min(l.dims.len())..], span)
    }

    /// Byte size of a value of type `ty` whose dimension lengths are `dims`.
    pub fn size_of_loc(&mut self, ty: &Type, dims: &[Value], span: Span) -> Res<Value> {
        if let Some(s) = size_of(&self.cx.checked.types, ty) {
            return Ok(self.iconst(s));
        }
        let base = crate::layout::base_elem(ty);
        let mut v = match size_of(&self.cx.checked.types, base) {
            Some(s) => self.iconst(s),
            None => return Err(self.cx.internal(span, "size of an unsized type")),
        };
        for d in dims {
            v = self.b.ins().imul(v, *d);
        }
        Ok(v)
    }

    /// Total byte size of place `l`.
    pub fn loc_size(&mut self, l: &Loc, span: Span) -> Res<Value> {
        let ty = l.ty.clone();
        let dims = l.dims.clone();
        self.size_of_loc(&ty, &dims, span)
    }

    fn subscript(&mut self, base: &Expr, index: &Expr, span: Span) -> Res<Loc> {
        if let ExprKind::Name(n) = &base.kind
            && let Some(Storage::ChanTable { depth, offset, len }) =
                self.cx.env.get(&self.cx.symbol(n)?).cloned()
        {
            let i = self.int_index(index)?;
            let ok = self
                .b
                .ins()
                .icmp_imm_s(IntCC::UnsignedLessThan, i, i64::from(len));
            self.check(ok, ErrorKind::Subscript, span);
            let f = self.frame_at(depth);
            let slot = self.b.ins().iadd_imm_s(f, i64::from(offset));
            let off = self.b.ins().imul_imm_s(i, i64::from(WORD_BYTES));
            let slot = self.b.ins().iadd(slot, off);
            let addr = self.b.ins().load(types::I64, mem(), slot, 0);
            let ty = self.cx.type_of(base)?;
            let ty = crate::layout::resolve(&self.cx.checked.types, &ty);
            return Ok(Loc {
                addr,
                ty: ty.elem().cloned().unwrap_or(Type::Error),
                dims: vec![],
            });
        }
        let b = self.place(base)?;
        let table = &self.cx.checked.types;
        if let Type::Named(id) = table.underlying(&b.ty)
            && let Some(TypeDefKind::Record { .. }) = table.defs.get(*id).map(|d| &d.kind)
        {
            let ExprKind::Name(field) = &index.kind else {
                return Err(self.cx.internal(span, "record field is not a name"));
            };
            let fields = record_fields(table, &b.ty)
                .ok_or_else(|| self.cx.internal(span, "record layout"))?;
            let (_, off, fty) = fields
                .into_iter()
                .find(|(n, _, _)| *n == field.text)
                .ok_or_else(|| self.cx.internal(span, "no such field"))?;
            let addr = self.b.ins().iadd_imm_s(b.addr, off);
            let fty = crate::layout::resolve(table, &fty);
            let dims = static_dims(&fty)
                .iter()
                .map(|d| self.iconst(i64::from(d.unwrap_or(0))))
                .collect();
            return Ok(Loc {
                addr,
                ty: fty,
                dims,
            });
        }
        let i = self.int_index(index)?;
        let Some(&n) = b.dims.first() else {
            return Err(self.cx.internal(span, "subscript of a non-array"));
        };
        let ok = self.b.ins().icmp(IntCC::UnsignedLessThan, i, n);
        self.check(ok, ErrorKind::Subscript, span);
        let es = self.elem_size(&b, span)?;
        let off = self.b.ins().imul(i, es);
        let addr = self.b.ins().iadd(b.addr, off);
        let ty = b.ty.elem().cloned().unwrap_or(Type::Error);
        Ok(Loc {
            addr,
            ty,
            dims: b.dims[1..].to_vec(),
        })
    }

    /// An integer expression widened to `i64` (for subscripts and counts).
    pub fn int_index(&mut self, e: &Expr) -> Res<Value> {
        let v = self.expr(e)?;
        Ok(self.widen_i64(v, e))
    }

    /// Widens an integer value of `e`'s type to `i64` (BYTE unsigned).
    pub fn widen_i64(&mut self, v: Value, e: &Expr) -> Value {
        let ty = self.b.func.dfg.value_type(v);
        if ty == types::I64 {
            return v;
        }
        let unsigned = matches!(
            self.cx
                .checked
                .types
                .prim(&self.cx.type_of(e).unwrap_or(Type::INT)),
            Some(occ_compiler::types::Prim::Byte | occ_compiler::types::Prim::Bool)
        );
        if unsigned {
            self.b.ins().uextend(types::I64, v)
        } else {
            self.b.ins().sextend(types::I64, v)
        }
    }

    fn slice(
        &mut self,
        base: &Expr,
        from: Option<&Expr>,
        count: Option<&Expr>,
        span: Span,
    ) -> Res<Loc> {
        let b = self.place(base)?;
        let Some(&n) = b.dims.first() else {
            return Err(self.cx.internal(span, "slice of a non-array"));
        };
        let f = match from {
            Some(e) => self.int_index(e)?,
            None => self.iconst(0),
        };
        let c = match count {
            Some(e) => self.int_index(e)?,
            None => self.b.ins().isub(n, f),
        };
        let ok1 = self.b.ins().icmp(IntCC::UnsignedLessThanOrEqual, f, n);
        let room = self.b.ins().isub(n, f);
        let ok2 = self.b.ins().icmp(IntCC::UnsignedLessThanOrEqual, c, room);
        let ok = self.b.ins().band(ok1, ok2);
        self.check(ok, ErrorKind::Segment, span);
        let es = self.elem_size(&b, span)?;
        let off = self.b.ins().imul(f, es);
        let addr = self.b.ins().iadd(b.addr, off);
        let elem = b.ty.elem().cloned().unwrap_or(Type::Error);
        let mut dims = vec![c];
        dims.extend_from_slice(&b.dims[1..]);
        Ok(Loc {
            addr,
            ty: Type::Array(None, Box::new(elem)),
            dims,
        })
    }

    /// Loads a scalar of type `ty` from `addr`.
    pub fn load_scalar(&mut self, ty: &Type, addr: Value, span: Span) -> Res<Value> {
        let p = self
            .cx
            .checked
            .types
            .prim(ty)
            .ok_or_else(|| self.cx.internal(span, "load of a non-scalar"))?;
        Ok(self.b.ins().load(cl_type(p), mem(), addr, 0))
    }

    /// Stores scalar `v` at `addr`.
    pub fn store_scalar(&mut self, v: Value, addr: Value) {
        self.b.ins().store(mem(), v, addr, 0);
    }

    /// Copies `size` bytes from `src` to `dst` (may overlap).
    pub fn copy_bytes(&mut self, dst: Value, src: Value, size: Value) {
        let cfg = self.cx.jit.module_target_config();
        self.b.call_memmove(cfg, dst, src, size);
    }
}
