//! The JIT: one `JITModule` (opt_level speed) with every native function of
//! [`occ_runtime::native::natives`] (the runtime entries, the predefine intrinsics and the
//! program's [`IntrinsicSet`]) imported, and a pool of reusable
//! `codegen::Context`/`FunctionBuilderContext` pairs (one per nesting level of functions being
//! lowered at the same time), in the shape of cranelift-jit-demo's `jit.rs`.

use std::collections::HashMap;

use cranelift_codegen::ir::{AbiParam, Signature, types};
use cranelift_codegen::settings::{self, Configurable};
use cranelift_frontend::FunctionBuilderContext;
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{FuncId, Linkage, Module, default_libcall_names};
use occ_runtime::abi::Entry;
use occ_runtime::intrinsic::{IntrinsicSet, MachineType};
use occ_runtime::native::{Native, natives};

use crate::error::CodegenError;

/// A context pair reused between functions.
pub struct FnContext {
    /// The function being built.
    pub ctx: cranelift_codegen::Context,
    /// The builder's scratch state.
    pub fcx: FunctionBuilderContext,
}

/// The module, the imported runtime entries and the context pool.
pub struct Jit {
    /// The JIT module that owns the generated code.
    pub module: JITModule,
    /// The import of each runtime entry, indexed by [`Entry`].
    imports: Vec<FuncId>,
    /// Intrinsic name to its import (the program's intrinsics and the predefine intrinsics).
    pub intrinsics: HashMap<&'static str, FuncId>,
    pool: Vec<FnContext>,
    next_name: u32,
}

fn cl_err(e: impl std::fmt::Display) -> CodegenError {
    CodegenError::Cranelift(e.to_string())
}

impl Jit {
    /// Creates the module and declares every runtime entry and every intrinsic of `set` as an
    /// import.
    pub fn new(set: &IntrinsicSet) -> Result<Jit, CodegenError> {
        // Step 1: the ISA, optimising for speed (Cranelift's default is "none").
        let mut flags = settings::builder();
        flags.set("opt_level", "speed").map_err(cl_err)?;
        flags.set("is_pic", "false").map_err(cl_err)?;
        let isa = cranelift_native::builder()
            .map_err(cl_err)?
            .finish(settings::Flags::new(flags))
            .map_err(cl_err)?;
        // Step 2: register every native function's symbol, then declare each as an import.
        let natives: Vec<_> = natives(set).collect();
        let mut jb = JITBuilder::with_isa(isa, default_libcall_names());
        for f in &natives {
            jb.symbol(&f.symbol, f.addr);
        }
        let mut module = JITModule::new(jb);
        let mut imports = Vec::with_capacity(Entry::ALL.len());
        let mut intrinsics = HashMap::new();
        for f in &natives {
            let mut sig = module.make_signature();
            sig.params
                .extend(f.params.iter().map(|m| AbiParam::new(machine_type(*m))));
            sig.returns
                .extend(f.result.map(|r| AbiParam::new(machine_type(r))));
            let id = module
                .declare_function(&f.symbol, Linkage::Import, &sig)
                .map_err(cl_err)?;
            match f.native {
                Native::Entry(_) => imports.push(id),
                Native::Intrinsic(i) => {
                    intrinsics.insert(i.name, id);
                }
            }
        }
        Ok(Jit {
            module,
            imports,
            intrinsics,
            pool: Vec::new(),
            next_name: 0,
        })
    }

    /// The import of runtime entry `e`.
    pub fn entry(&self, e: Entry) -> FuncId {
        self.imports[e as usize]
    }

    /// The signature of every compiled PROC and PAR branch: `(ws, node) -> status`.
    pub fn proc_signature(&self) -> Signature {
        let mut sig = self.module.make_signature();
        sig.params.push(AbiParam::new(types::I64));
        sig.params.push(AbiParam::new(types::I64));
        sig.returns.push(AbiParam::new(types::I64));
        sig
    }

    /// Declares a new compiled function (named uniquely from `hint`).
    pub fn declare(&mut self, hint: &str) -> Result<FuncId, CodegenError> {
        self.next_name += 1;
        let name = format!("occ{}_{}", self.next_name, hint);
        let sig = self.proc_signature();
        self.module
            .declare_function(&name, Linkage::Local, &sig)
            .map_err(cl_err)
    }

    /// Takes a context pair from the pool (or makes one).
    pub fn take_context(&mut self) -> FnContext {
        self.pool.pop().unwrap_or_else(|| FnContext {
            ctx: self.module.make_context(),
            fcx: FunctionBuilderContext::new(),
        })
    }

    /// Defines function `id` from the built context, then clears the context and returns it to
    /// the pool.
    pub fn define(&mut self, id: FuncId, mut fc: FnContext) -> Result<(), CodegenError> {
        let r = self.module.define_function(id, &mut fc.ctx);
        if let Err(e) = &r {
            let text = match e {
                cranelift_module::ModuleError::Compilation(c) => {
                    format!("{c:?}\n{}", fc.ctx.func.display())
                }
                other => other.to_string(),
            };
            self.module.clear_context(&mut fc.ctx);
            self.pool.push(fc);
            return Err(CodegenError::Cranelift(text));
        }
        self.module.clear_context(&mut fc.ctx);
        self.pool.push(fc);
        Ok(())
    }

    /// Finalizes every definition (relocations, executable memory).
    pub fn finalize(&mut self) -> Result<(), CodegenError> {
        self.module.finalize_definitions().map_err(cl_err)
    }
}

/// The Cranelift type of an intrinsic argument or result.
pub fn machine_type(m: MachineType) -> types::Type {
    match m {
        MachineType::I64 => types::I64,
        MachineType::F32 => types::F32,
        MachineType::F64 => types::F64,
    }
}

impl Jit {
    /// The target's frontend configuration (for memcpy/memmove calls).
    pub fn module_target_config(&self) -> cranelift_codegen::isa::TargetFrontendConfig {
        self.module.target_config()
    }
}
