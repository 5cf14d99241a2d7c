//! Every native function compiled code calls, in one descriptor: the runtime [`Entry`] points,
//! the intrinsics of the program's [`IntrinsicSet`] and the predefine intrinsics
//! ([`crate::intrinsic::predefine`]). The code generator links what [`natives`] lists and nothing
//! else.

use crate::abi::{AbiType, Entry};
use crate::entries;
use crate::intrinsic::predefine::PREDEFINES;
use crate::intrinsic::{Intrinsic, IntrinsicSet, MachineType};

/// What a [`NativeFn`] is.
#[derive(Clone, Copy, Debug)]
pub enum Native {
    /// A runtime entry point.
    Entry(Entry),
    /// An intrinsic (of the program's set, or a predefine's).
    Intrinsic(&'static Intrinsic),
}

/// One native function as it is linked: symbol, machine signature and address.
#[derive(Clone, Debug)]
pub struct NativeFn {
    /// What it is.
    pub native: Native,
    /// The linker symbol (unique among the functions [`natives`] lists).
    pub symbol: String,
    /// The machine parameters, in order.
    pub params: Vec<MachineType>,
    /// The machine result, if any.
    pub result: Option<MachineType>,
    /// The function's address.
    pub addr: *const u8,
}

impl NativeFn {
    /// The descriptor of runtime entry `e`.
    pub fn entry(e: Entry) -> NativeFn {
        let s = e.signature();
        let machine = |_: AbiType| MachineType::I64;
        NativeFn {
            native: Native::Entry(e),
            symbol: s.name.to_string(),
            params: s.params.iter().map(|p| machine(*p)).collect(),
            result: Some(machine(s.ret)),
            addr: entries::address(e),
        }
    }

    /// The descriptor of intrinsic `i`.
    pub fn intrinsic(i: &'static Intrinsic) -> NativeFn {
        NativeFn {
            native: Native::Intrinsic(i),
            symbol: format!("occ_intrinsic_{}", i.name.replace('.', "_")),
            params: i.machine_params(),
            result: i.result,
            addr: i.addr,
        }
    }
}

/// Every native function a program compiled with `set` may call: the runtime entries (in
/// [`Entry::ALL`] order), the predefine intrinsics, then the set's intrinsics (each name once: a
/// set entry with a predefine intrinsic's name is left out).
pub fn natives(set: &IntrinsicSet) -> impl Iterator<Item = NativeFn> + '_ {
    let entries = Entry::ALL.iter().map(|e| NativeFn::entry(*e));
    let predefines = PREDEFINES.iter().map(NativeFn::intrinsic);
    let others = set
        .iter()
        .filter(|i| PREDEFINES.iter().all(|p| p.name != i.name))
        .map(NativeFn::intrinsic);
    entries.chain(predefines).chain(others)
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::intrinsic::INTRINSICS;

    #[test]
    fn symbols_are_unique_and_entries_come_first_in_order() {
        let all: Vec<NativeFn> = natives(&IntrinsicSet::new()).collect();
        assert_eq!(
            all.len(),
            Entry::ALL.len() + PREDEFINES.len() + INTRINSICS.len()
        );
        for (i, f) in all.iter().enumerate() {
            assert!(
                all[..i].iter().all(|o| o.symbol != f.symbol),
                "{}",
                f.symbol
            );
            assert!(!f.addr.is_null());
            if let Native::Entry(e) = f.native {
                assert_eq!(e as usize, i);
            }
        }
    }
}
