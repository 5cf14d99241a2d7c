//! Lowering of checked occam to Cranelift IR: the [`Compiler`] (whole-program state) and the
//! [`Tr`] function translator, whose `match` over process kinds delegates to one module per
//! construct family.
//!
//! Storage rules (see also `crate::frame`): every variable lives at a fixed byte offset in the
//! workspace of the function that declares it; a function reaches the frames of lexically
//! enclosing functions through word 0 of its frame (the static link: the parent's frame for a PAR
//! branch, the declaring frame for a PROC). Values are only held in Cranelift registers between
//! blocking points.

mod alt;
mod asm;
mod bits;
mod call;
mod construct;
mod decl;
mod expr;
mod io;
mod ops;
mod par;
mod place;
mod predefined;
mod process;

use std::collections::HashMap;

use cranelift_codegen::ir::{
    Block, FuncRef, InstBuilder, MemFlagsData, UserFuncName, Value, condcodes::IntCC, types,
};
use cranelift_frontend::{FunctionBuilder, Switch};
use cranelift_module::{FuncId, Module};
use occ_compiler::CheckedProgram;
use occ_compiler::checked::SymbolId;
use occ_compiler::consteval::Value as Const;
use occ_compiler::types::Type;
use occ_grammar::ast::{self, Span};
use occ_grammar::source_map::SourceMap;
use occ_runtime::ErrorKind;
use occ_runtime::abi::{Entry, NODE_POLLS_LEFT_OFFSET, Status, slot, word_offset, yield_flag};
use occ_runtime::program::{ChannelName, ProgramInfo};

use crate::error::CodegenError;
use crate::frame::{FIRST_LOCAL, Frame, Size};
use crate::jit::Jit;

pub use place::Loc;

/// Result type of lowering.
pub type Res<T> = Result<T, CodegenError>;

/// Where a name's value lives.
#[derive(Clone, Debug)]
pub enum Storage {
    /// The value is at byte `offset` of the frame of the function at lexical `depth`.
    Var {
        /// Lexical depth of the owning function.
        depth: u32,
        /// Byte offset in its frame.
        offset: i32,
    },
    /// The word at `offset` holds the value's address; for arrays the following words hold the
    /// length of each dimension.
    Ref {
        /// Lexical depth of the owning function.
        depth: u32,
        /// Byte offset of the address word.
        offset: i32,
    },
    /// A table of channels abbreviated (`ins IS [d, c] :`): the `len` words at `offset` hold
    /// the channels' addresses, so that `ins[i]` is the channel itself, not a copy of its word.
    ChanTable {
        /// Lexical depth of the owning function.
        depth: u32,
        /// Byte offset of the first address word.
        offset: i32,
        /// The number of channels.
        len: u32,
    },
    /// A compile-time constant.
    Const(Const),
    /// A compiled PROC.
    Proc(ProcEntry),
    /// A FUNCTION, expanded inline at each call.
    Function(std::rc::Rc<ast::Decl>),
}

/// A compiled PROC: its function, frame size and parameter slots.
#[derive(Clone, Debug)]
pub struct ProcEntry {
    /// The compiled function.
    pub id: FuncId,
    /// Words above Wptr its frame needs and the most vectors it holds (including its callees).
    pub size: Size,
    /// Lexical depth of its body (its static link is the frame at `depth - 1`).
    pub depth: u32,
    /// Byte offset of each parameter's slot in its frame, and whether it is passed by value.
    pub params: Vec<(i32, bool)>,
    /// Parameter types.
    pub param_types: Vec<Type>,
}

/// The (file, line) of a span in `map`.
fn file_line(map: &SourceMap, span: Span) -> (String, u32) {
    match map.locate(span) {
        Some(l) => (
            map.files
                .get(l.file)
                .map_or_else(String::new, |f| f.path.clone()),
            l.line as u32,
        ),
        None => (String::from("?"), 0),
    }
}

/// Whole-program lowering state.
pub struct Compiler<'p> {
    /// The checked program.
    pub checked: &'p CheckedProgram,
    /// Spans back to files and lines.
    pub map: &'p SourceMap,
    /// The JIT module.
    pub jit: Jit,
    /// Storage of every symbol in scope so far.
    pub env: HashMap<SymbolId, Storage>,
    /// Declaration span to symbol.
    pub decl_syms: HashMap<Span, SymbolId>,
    /// Program tables for the runtime.
    pub info: ProgramInfo,
    /// Constant data referenced by address from compiled code.
    pub data: Vec<Box<[u8]>>,
    /// Every compiled function: id, runtime name, resume locations, channels declared.
    pub funcs: Vec<(FuncId, String, Vec<u32>, Vec<ChannelName>)>,
    /// The name of the PROC being compiled (PAR branches report it).
    pub proc_name: String,
    /// Each `#PRAGMA EXTERNAL` routine's intrinsic (see [`crate::bind`]).
    pub externals: HashMap<SymbolId, &'static occ_runtime::intrinsic::Intrinsic>,
    /// The network layout, once the `PLACED PAR` is compiled.
    pub network: Option<crate::network::NetworkLayout>,
    /// The routines the entry PROC reaches: the only ones compiled.
    pub reach: crate::reach::Reach,
    locations: HashMap<(usize, usize), u32>,
}

impl<'p> Compiler<'p> {
    /// Starts compiling the routines of `checked` that `reach` needs (spans mapped through
    /// `map`) with the intrinsics of `set`; fails with every EXTERNAL that they call and that
    /// cannot be bound (see [`crate::bind`]).
    pub fn new(
        checked: &'p CheckedProgram,
        map: &'p SourceMap,
        set: &occ_runtime::intrinsic::IntrinsicSet,
        reach: crate::reach::Reach,
    ) -> Res<Compiler<'p>> {
        let decl_syms = checked.symbols.iter().map(|(id, s)| (s.span, id)).collect();
        let bindings = crate::bind::bind_some(checked, set, |id| reach.needs(checked, id));
        if !bindings.errors.is_empty() {
            return Err(CodegenError::Link(bindings.errors));
        }
        Ok(Compiler {
            checked,
            map,
            jit: Jit::new(set)?,
            externals: bindings.bound,
            env: HashMap::new(),
            decl_syms,
            info: ProgramInfo::default(),
            data: Vec::new(),
            funcs: Vec::new(),
            proc_name: String::new(),
            locations: HashMap::new(),
            network: None,
            reach,
        })
    }

    /// The (file, line) of a span.
    pub fn file_line(&self, span: Span) -> (String, u32) {
        file_line(self.map, span)
    }

    /// The location index (for `rt_error` and resume tables) of a span.
    pub fn location(&mut self, span: Span) -> u32 {
        let key = self
            .map
            .locate(span)
            .map_or((usize::MAX, 0), |l| (l.file, l.line));
        if let Some(i) = self.locations.get(&key) {
            return *i;
        }
        let (file, line) = self.file_line(span);
        let i = self.info.add_location(&file, line);
        self.locations.insert(key, i);
        i
    }

    /// An "unsupported" error at `span`.
    pub fn unsupported(&self, span: Span, what: impl Into<String>) -> CodegenError {
        CodegenError::Unsupported {
            span,
            what: what.into(),
        }
    }

    /// An "internal" error at `span`.
    pub fn internal(&self, span: Span, what: impl Into<String>) -> CodegenError {
        CodegenError::Internal {
            span,
            what: what.into(),
        }
    }

    /// Whether the declaration of routine `name` is compiled: something reaches it.
    pub fn needed(&self, name: &ast::Name) -> Res<bool> {
        let sym = self.symbol(name)?;
        Ok(self.reach.needs(self.checked, sym))
    }

    /// The symbol a name occurrence denotes.
    pub fn symbol(&self, name: &ast::Name) -> Res<SymbolId> {
        self.checked
            .names
            .get(&name.span)
            .or_else(|| self.decl_syms.get(&name.span))
            .copied()
            .ok_or_else(|| self.internal(name.span, format!("no symbol for `{}`", name.text)))
    }

    /// The checker's type of an expression.
    pub fn type_of(&self, e: &ast::Expr) -> Res<Type> {
        self.checked
            .expr_types
            .get(&e.span)
            .cloned()
            .ok_or_else(|| self.internal(e.span, "expression has no type"))
    }

    /// Keeps `bytes` alive for the program's lifetime and returns their address.
    pub fn intern(&mut self, bytes: Vec<u8>) -> i64 {
        let b = bytes.into_boxed_slice();
        let addr = b.as_ptr() as i64;
        self.data.push(b);
        addr
    }

    /// Compiles one resumable function at lexical `depth`; `body` lowers its code and must end
    /// the current block with a return. Returns the function and its size.
    pub fn function(
        &mut self,
        name: &str,
        depth: u32,
        frame: Frame,
        span: Span,
        body: impl FnOnce(&mut Tr<'_, 'p>) -> Res<()>,
    ) -> Res<(FuncId, Size)> {
        let id = self.jit.declare(&name.replace('.', "_"))?;
        let mut fc = self.jit.take_context();
        fc.ctx.func.signature = self.jit.proc_signature();
        fc.ctx.func.name = UserFuncName::user(0, id.as_u32());
        let start_loc = self.location(span);
        let built = {
            let mut b = FunctionBuilder::new(&mut fc.ctx.func, &mut fc.fcx);
            let entry = b.create_block();
            b.append_block_params_for_function_params(entry);
            b.switch_to_block(entry);
            let ws = b.block_params(entry)[0];
            let node = b.block_params(entry)[1];
            let dispatch = b.create_block();
            let start = b.create_block();
            let exit = b.create_block();
            b.append_block_param(exit, types::I64);
            b.ins().jump(dispatch, &[]);
            b.switch_to_block(start);
            let mut tr = Tr {
                cx: self,
                b,
                ws,
                node,
                depth,
                frame,
                resumes: vec![(start, start_loc)],
                refs: HashMap::new(),
                exit,
                in_expr: 0,
                no_poll: 0,
                held: None,
                channels: Vec::new(),
                asm_area: None,
                vectors: Vec::new(),
            };
            tr.reserve_asm_area(span);
            let r = body(&mut tr);
            r.map(|()| tr.finish(dispatch))
        };
        match built {
            Ok((size, resumes, channels)) => {
                self.jit.define(id, fc)?;
                let shown = if self.proc_name.is_empty() {
                    name.to_string()
                } else {
                    self.proc_name.clone()
                };
                self.funcs.push((id, shown, resumes, channels));
                Ok((id, size))
            }
            Err(e) => {
                self.jit.module.clear_context(&mut fc.ctx);
                Err(e)
            }
        }
    }
}

/// The translator of one function.
pub struct Tr<'a, 'p> {
    /// Whole-program state.
    pub cx: &'a mut Compiler<'p>,
    /// The function builder.
    pub b: FunctionBuilder<'a>,
    /// The frame's workspace pointer.
    pub ws: Value,
    /// The node.
    pub node: Value,
    /// This function's lexical depth.
    pub depth: u32,
    /// Frame allocation.
    pub frame: Frame,
    /// Resume blocks by index, with their location.
    pub resumes: Vec<(Block, u32)>,
    refs: HashMap<FuncId, FuncRef>,
    exit: Block,
    /// Non-zero inside an expression (VALOF): no blocking points may be emitted.
    pub in_expr: u32,
    /// Non-zero while enabling or disabling ALT guards: loops do not poll.
    pub no_poll: u32,
    /// Channels declared in this frame (for deadlock reports).
    pub channels: Vec<ChannelName>,
    /// While lowering the input of an extended rendezvous (`c ?? x`): the frame offset of the
    /// word that holds the outputter not yet released (see [`Entry::Xin`]).
    pub held: Option<i32>,
    /// The workspace area of the function's `ASM` blocks: the byte offset of their Wptr and
    /// the 32-bit words reserved below and above it.
    pub asm_area: Option<(i32, u32, u32)>,
    /// The vectors of the scopes open at this point: the frame offset of each one's address
    /// word and its bytes (see [`crate::frame::VECTOR_BYTES`]).
    pub vectors: Vec<(i32, i64)>,
}

/// Memory flags for workspace data (not necessarily aligned).
pub fn mem() -> MemFlagsData {
    let mut f = MemFlagsData::new();
    f.set_notrap();
    f
}

impl<'p> Tr<'_, 'p> {
    /// Emits the entry dispatch and the exit block, and finishes the function.
    fn finish(mut self, dispatch: Block) -> (Size, Vec<u32>, Vec<ChannelName>) {
        self.b.switch_to_block(self.exit);
        let st = self.b.block_params(self.exit)[0];
        self.b.ins().return_(&[st]);
        self.b.switch_to_block(dispatch);
        let iptr = self.load_slot(slot::IPTR);
        let mut sw = Switch::new();
        for (i, (blk, _)) in self.resumes.iter().enumerate() {
            sw.set_entry(i as u128, *blk);
        }
        let bad = self.b.create_block();
        sw.emit(&mut self.b, iptr, bad);
        self.b.switch_to_block(bad);
        let v = self.b.ins().iconst(types::I64, Status::BAD_RESUME.0);
        self.b.ins().return_(&[v]);
        self.b.seal_all_blocks();
        let cfg = self.cx.jit.module_target_config();
        self.b.finalize(cfg);
        (
            self.frame.size(),
            self.resumes.iter().map(|r| r.1).collect(),
            self.channels,
        )
    }

    /// A reference to runtime entry `e` in this function.
    pub fn rt(&mut self, e: Entry) -> FuncRef {
        let id = self.cx.jit.entry(e);
        self.func_ref(id)
    }

    /// A reference to function `id` in this function.
    pub fn func_ref(&mut self, id: FuncId) -> FuncRef {
        if let Some(r) = self.refs.get(&id) {
            return *r;
        }
        let r = self.cx.jit.module.declare_func_in_func(id, self.b.func);
        self.refs.insert(id, r);
        r
    }

    /// Calls a non-blocking runtime entry and returns its result.
    pub fn call_rt(&mut self, e: Entry, args: &[Value]) -> Value {
        let f = self.rt(e);
        let c = self.b.ins().call(f, args);
        self.b.inst_results(c)[0]
    }

    /// An `i64` constant.
    pub fn iconst(&mut self, v: i64) -> Value {
        self.b.ins().iconst(types::I64, v)
    }

    /// Loads workspace slot `s` (a word offset) of this frame.
    pub fn load_slot(&mut self, s: isize) -> Value {
        self.b
            .ins()
            .load(types::I64, MemFlagsData::trusted(), self.ws, word_offset(s))
    }

    /// Stores `v` into workspace slot `s` of the frame at `base`.
    pub fn store_slot_at(&mut self, base: Value, s: isize, v: Value) {
        self.b
            .ins()
            .store(MemFlagsData::trusted(), v, base, word_offset(s));
    }

    /// Allocates a new resume point at `span`; returns its index and block.
    pub fn new_resume(&mut self, span: Span) -> (i64, Block) {
        let loc = self.cx.location(span);
        let blk = self.b.create_block();
        self.resumes.push((blk, loc));
        ((self.resumes.len() - 1) as i64, blk)
    }

    /// Calls blocking entry `e` following the blocking-point rule and continues after it.
    pub fn blocking(&mut self, e: Entry, args: &[Value], span: Span) -> Res<()> {
        if self.in_expr > 0 {
            return Err(self
                .cx
                .unsupported(span, "a blocking operation inside an expression (VALOF)"));
        }
        let (idx, cont) = self.new_resume(span);
        let iv = self.iconst(idx);
        self.store_slot_at(self.ws, slot::IPTR, iv);
        let f = self.rt(e);
        let c = self.b.ins().call(f, args);
        let st = self.b.inst_results(c)[0];
        self.b.ins().brif(st, self.exit, &[st.into()], cont, &[]);
        self.b.switch_to_block(cont);
        Ok(())
    }

    /// Calls a compiled function natively following the frame-chain rule.
    pub fn call_native(&mut self, id: FuncId, callee_ws: Value, span: Span) -> Res<()> {
        let (idx, cont) = self.new_resume(span);
        let iv = self.iconst(idx);
        self.store_slot_at(self.ws, slot::IPTR, iv);
        let f = self.func_ref(id);
        let c = self.b.ins().call(f, &[callee_ws, self.node]);
        let st = self.b.inst_results(c)[0];
        self.b.ins().brif(st, self.exit, &[st.into()], cont, &[]);
        self.b.switch_to_block(cont);
        Ok(())
    }

    /// Returns `st` from the function (ends the current block; continues in a dead block).
    pub fn ret(&mut self, st: Value) {
        self.b.ins().jump(self.exit, &[st.into()]);
        let dead = self.b.create_block();
        self.b.switch_to_block(dead);
    }

    /// Halts with runtime error `kind` at `span` unless `ok` is non-zero.
    pub fn check(&mut self, ok: Value, kind: ErrorKind, span: Span) {
        let fail = self.b.create_block();
        let cont = self.b.create_block();
        self.b.ins().brif(ok, cont, &[], fail, &[]);
        self.b.set_cold_block(fail);
        self.b.switch_to_block(fail);
        self.halt(kind, span);
        self.b.switch_to_block(cont);
    }

    /// Halts with runtime error `kind` at `span` (ends the current block).
    pub fn halt(&mut self, kind: ErrorKind, span: Span) {
        let loc = self.cx.location(span);
        let k = self.iconst(kind as i64);
        let l = self.iconst(i64::from(loc));
        let st = self.call_rt(Entry::Error, &[self.node, self.ws, k, l]);
        self.b.ins().jump(self.exit, &[st.into()]);
    }

    /// The timeslice poll at a loop back-edge; `head` is a resume point with index `idx`.
    pub fn poll(&mut self, idx: i64, head: Block) {
        if self.in_expr > 0 || self.no_poll > 0 || idx < 0 {
            self.b.ins().jump(head, &[]);
            return;
        }
        let flag = self.b.ins().load(
            types::I32,
            MemFlagsData::trusted(),
            self.node,
            occ_runtime::abi::YIELD_FLAG_OFFSET,
        );
        let (slow, count, call) = (
            self.b.create_block(),
            self.b.create_block(),
            self.b.create_block(),
        );
        self.b.ins().brif(flag, slow, &[], head, &[]);
        // Timeslicing by count: one poll fewer left, and no call until none is.
        self.b.set_cold_block(slow);
        self.b.switch_to_block(slow);
        let counting = self
            .b
            .ins()
            .icmp_imm_s(IntCC::Equal, flag, i64::from(yield_flag::COUNT));
        self.b.ins().brif(counting, count, &[], call, &[]);
        self.b.set_cold_block(count);
        self.b.switch_to_block(count);
        let left = self.b.ins().load(
            types::I32,
            MemFlagsData::trusted(),
            self.node,
            NODE_POLLS_LEFT_OFFSET,
        );
        let left = self.b.ins().iadd_imm_s(left, -1);
        self.b.ins().store(
            MemFlagsData::trusted(),
            left,
            self.node,
            NODE_POLLS_LEFT_OFFSET,
        );
        self.b.ins().brif(left, head, &[], call, &[]);
        // A request, or the counted timeslice.
        self.b.set_cold_block(call);
        self.b.switch_to_block(call);
        let iv = self.iconst(idx);
        self.store_slot_at(self.ws, slot::IPTR, iv);
        let st = self.call_rt(Entry::Timeslice, &[self.node, self.ws]);
        self.b.ins().brif(st, self.exit, &[st.into()], head, &[]);
    }

    /// A loop head block: a resume point (for the poll) unless inside an expression.
    pub fn loop_head(&mut self, span: Span) -> (i64, Block) {
        if self.in_expr > 0 || self.no_poll > 0 {
            (-1, self.b.create_block())
        } else {
            self.new_resume(span)
        }
    }

    /// The frame pointer of the function at lexical `depth` (following static links).
    pub fn frame_at(&mut self, depth: u32) -> Value {
        let mut v = self.ws;
        for _ in depth..self.depth {
            v = self.b.ins().load(types::I64, MemFlagsData::trusted(), v, 0);
        }
        v
    }

    /// Address of byte `offset` of this frame.
    pub fn local_addr(&mut self, offset: i32) -> Value {
        self.b.ins().iadd_imm_s(self.ws, i64::from(offset))
    }

    /// Compares an i64 against zero: non-zero gives 1.
    pub fn is_nonzero(&mut self, v: Value) -> Value {
        self.b.ins().icmp_imm_s(IntCC::NotEqual, v, 0)
    }

    /// Lowers the body of a PROC or branch with its frame's first local slot after the fixed
    /// words.
    pub fn first_local() -> i32 {
        FIRST_LOCAL
    }
}
