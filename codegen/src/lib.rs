//! Native code generation for checked occam programs through Cranelift: each PROC (and each PAR
//! branch) becomes a resumable function over its workspace, driven by the `occ-runtime`
//! scheduler (see `occ_runtime::abi` for the contract).
//!
//! Pipeline: [`compile`] walks the checked AST ([`lower`]) with frames laid out by [`frame`] and
//! values typed by [`layout`], defines the functions in one JIT module ([`jit`]) and returns a
//! [`Compiled`] program; [`Compiled::run`] runs its entry PROC on a fresh node with the three
//! host byte channels.

#![deny(missing_docs)]

pub mod bind;
pub mod error;
pub mod frame;
pub mod jit;
pub mod layout;
pub mod lower;
pub mod network;
pub mod reach;
mod spread;

use std::sync::Arc;

use occ_compiler::CheckedProgram;
use occ_compiler::types::Type;
use occ_grammar::ast::{self, DeclKind};
use occ_grammar::source_map::SourceMap;
use occ_runtime::abi::{self, ProcFn, Word};
pub use occ_runtime::intrinsic::IntrinsicSet;
use occ_runtime::program::CodeInfo;
use occ_runtime::{HostIo, Node, NodeConfig, ProgramInfo, RunError, Stats};

pub use error::CodegenError;
use lower::{Compiler, Storage};

/// A compiled program: native code, constant data and the runtime's tables.
pub struct Compiled {
    module: Option<cranelift_jit::JITModule>,
    _data: Vec<Box<[u8]>>,
    /// The entry PROC's code.
    pub entry: ProcFn,
    /// The entry PROC's name.
    pub entry_name: String,
    /// Words of workspace the entry PROC needs above Wptr.
    pub entry_words: u32,
    /// The most bytes of vectors (large arrays, taken from node memory as their declarations
    /// run: `frame::VECTOR_BYTES`) the entry PROC can hold at once.
    pub entry_vectors: i64,
    /// Byte offsets of the entry PROC's channel parameters in its frame.
    pub entry_params: Vec<i32>,
    /// Every parameter of the entry PROC: byte offset, passed by value, type.
    pub entry_param_slots: Vec<(i32, bool, Type)>,
    /// The network its `PLACED PAR` configures, if any.
    pub network: Option<network::NetworkLayout>,
    /// Tables for error and deadlock reports.
    pub info: Arc<ProgramInfo>,
    /// The routines left out: nothing the entry PROC runs calls them ([`reach`]).
    pub left_out: reach::LeftOut,
}

impl Drop for Compiled {
    fn drop(&mut self) {
        if let Some(m) = self.module.take() {
            // SAFETY: no node runs this program's code any more: nodes borrow `self` in `run`.
            unsafe { m.free_memory() };
        }
    }
}

/// The whole front end, IO-free: preprocesses, parses and checks the file `path` whose text is
/// `text` ([`occ_compiler::check_source`]), then binds its `#PRAGMA EXTERNAL` routines to
/// `intrinsics` ([`bind::bind_externals`]), so that a program that passes can be compiled with
/// [`compile_with`] and the same set. `occ check`, `occ run`, `occ test`, the tests and the
/// benchmarks all start here.
pub fn front_end(
    path: &str,
    text: &str,
    loader: &mut dyn occ_grammar::preprocess::Loader,
    intrinsics: &IntrinsicSet,
) -> occ_compiler::Front {
    let mut front = occ_compiler::check_source(path, text, loader);
    if let Some(checked) = &front.checked {
        let bindings = bind::bind_externals(checked, intrinsics);
        if !bindings.errors.is_empty() {
            front.diagnostics.extend(bindings.errors);
            front.checked = None;
        }
    }
    front
}

/// Compiles `program` (checked as `checked`, spans mapped by `map`) with the runtime's own
/// intrinsics only; see [`compile_with`].
pub fn compile(
    program: &ast::Program,
    checked: &CheckedProgram,
    map: &SourceMap,
) -> Result<Compiled, CodegenError> {
    compile_with(program, checked, map, &IntrinsicSet::new())
}

/// Compiles `program` (checked as `checked`, spans mapped by `map`), binding its
/// `#PRAGMA EXTERNAL` routines to the intrinsics of `intrinsics` ([`bind`]); the entry point is
/// its last top-level PROC, which must take up to three `CHAN BYTE` parameters (keyboard,
/// screen, error). Only the routines the entry PROC reaches are compiled and bound
/// ([`reach`]): an EXTERNAL that no linked table has is an error here only where reachable
/// code calls it (the front end reports every call).
pub fn compile_with(
    program: &ast::Program,
    checked: &CheckedProgram,
    map: &SourceMap,
    intrinsics: &IntrinsicSet,
) -> Result<Compiled, CodegenError> {
    compile_keeping(program, checked, map, intrinsics, false)
}

/// [`compile_with`], or with `everything` every PROC compiled and every EXTERNAL bound whether
/// or not anything calls it (`occ run --all-routines`: the old behaviour, for comparison).
pub fn compile_keeping(
    program: &ast::Program,
    checked: &CheckedProgram,
    map: &SourceMap,
    intrinsics: &IntrinsicSet,
    everything: bool,
) -> Result<Compiled, CodegenError> {
    let entry = program.decls.iter().rev().find_map(|d| match &d.kind {
        DeclKind::Proc { name, .. } => Some(name),
        _ => None,
    });
    let name = entry.ok_or(CodegenError::NoEntry)?;
    let entry_sym = checked
        .names
        .get(&name.span)
        .copied()
        .or_else(|| {
            checked
                .symbols
                .iter()
                .find(|(_, s)| s.span == name.span)
                .map(|(id, _)| id)
        })
        .ok_or(CodegenError::NoEntry)?;
    let reach = if everything {
        reach::Reach::everything(checked)
    } else {
        reach::reach(checked, entry_sym)
    };
    let mut cx = Compiler::new(checked, map, intrinsics, reach)?;
    for d in &program.decls {
        match &d.kind {
            DeclKind::Proc { name, .. } => {
                if cx.needed(name)? {
                    cx.compile_proc(d, 1)?;
                }
            }
            DeclKind::Function { name, .. } if !cx.needed(name)? => {}
            DeclKind::Function { name, .. } => {
                let sym = cx.symbol(name)?;
                cx.env
                    .insert(sym, Storage::Function(std::rc::Rc::new(d.clone())));
            }
            DeclKind::Abbrev { name, .. } => {
                let sym = cx.symbol(name)?;
                match &checked.symbols[sym].kind {
                    occ_compiler::checked::SymbolKind::Val { value: Some(c) } => {
                        cx.env.insert(sym, Storage::Const(c.clone()));
                    }
                    _ => {
                        return Err(cx.unsupported(d.span, "a non-constant top-level abbreviation"));
                    }
                }
            }
            DeclKind::DataType { .. } | DeclKind::Protocol { .. } => {}
            _ => return Err(cx.unsupported(d.span, "this top-level declaration")),
        }
    }
    let sym = cx.symbol(name)?;
    let Some(Storage::Proc(e)) = cx.env.get(&sym).cloned() else {
        return Err(CodegenError::NoEntry);
    };
    let host_entry = e.params.len() <= 3 && e.param_types.iter().all(network::is_byte_chan);
    let node_entry = e.param_types.len() >= 4
        && matches!(e.param_types[2], Type::Array(None, ref t) if matches!(**t, Type::Chan(..)));
    if !host_entry && !node_entry {
        return Err(CodegenError::BadEntry {
            name: name.text.clone(),
            span: name.span,
        });
    }
    cx.jit.finalize()?;
    let mut info = std::mem::take(&mut cx.info);
    for (id, pname, resumes, channels) in &cx.funcs {
        let code = cx.jit.module.get_finalized_function(*id);
        // SAFETY: every compiled function has the ProcFn signature.
        let f: ProcFn = unsafe { std::mem::transmute::<*const u8, ProcFn>(code) };
        let mut p = CodeInfo::new(pname, f);
        p.resume_locations = resumes.clone();
        p.channels = channels.clone();
        info.procs.push(p);
    }
    let code = cx.jit.module.get_finalized_function(e.id);
    // SAFETY: as above.
    let entry_fn: ProcFn = unsafe { std::mem::transmute::<*const u8, ProcFn>(code) };
    let Compiler {
        jit,
        data,
        network,
        reach,
        ..
    } = cx;
    Ok(Compiled {
        module: Some(jit.module),
        _data: data,
        entry: entry_fn,
        entry_name: name.text.clone(),
        entry_words: e.size.words,
        entry_vectors: e.size.vectors,
        entry_params: if host_entry {
            e.params.iter().map(|p| p.0).collect()
        } else {
            Vec::new()
        },
        entry_param_slots: e
            .params
            .iter()
            .zip(&e.param_types)
            .map(|(&(off, by_value), t)| (off, by_value, t.clone()))
            .collect(),
        network,
        info: Arc::new(info),
        left_out: reach.left_out,
    })
}

impl Compiled {
    /// Whether the entry PROC is a node program for [`Compiled::run_topology`] rather than a
    /// program of the host's three byte channels.
    pub fn is_node_program(&self) -> bool {
        self.network.is_none() && self.entry_params.len() < self.entry_param_slots.len()
    }

    /// Runs the entry PROC on a new node with `host` bound to its channels; returns the outcome
    /// and the node's counters.
    pub fn run(&self, config: NodeConfig, host: HostIo) -> (Result<(), RunError>, Stats) {
        let mut node = Node::new(config, self.info.clone(), host);
        let chans = node.host_channels();
        let ws =
            match node.alloc_workspace(self.entry_words as usize + abi::frame::ENTRY_SPARE_WORDS) {
                Ok(ws) => ws,
                Err(e) => return (Err(e), node.stats().clone()),
            };
        // SAFETY: `ws` has `entry_words` words above it and the header below; the parameter
        // offsets are inside the frame.
        unsafe {
            *ws.offset(abi::frame::STATIC_LINK) = 0;
            *ws.offset(abi::frame::JOIN) = 0;
            for (off, ch) in self.entry_params.iter().zip(chans) {
                *ws.byte_offset(*off as isize) = ch as Word;
            }
            node.spawn(ws, self.entry);
        }
        let r = node.run();
        (r, node.stats().clone())
    }
}
