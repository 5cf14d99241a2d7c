//! Native intrinsics: Rust functions that occam code calls with occam parameters.
//!
//! [`INTRINSICS`] is the one table the compiler and the runtime share. Each entry gives the occam
//! name, the occam parameter kinds in order, the result kind (for FUNCTIONs) and the function's
//! address. The machine signature follows from the kinds ([`ParamKind::machine`]):
//! - `VAL INT`/`BYTE`/`BOOL` pass one `i64` word (BOOL: 0 or 1; BYTE: 0..255);
//! - `VAL REAL32`/`REAL64` pass an `f32`/`f64`;
//! - an array (`VAL []T` or `[]T`) passes two words, the address of element 0 and the element
//!   count;
//! - `RESULT`/`VAR` scalars pass the address of a word-sized temporary holding the variable's
//!   value on entry, which the intrinsic may read and writes (INT and BOOL: a whole `i64` word,
//!   BOOL 0 or 1; REAL32: an `f32` at the address); the caller copies it to the variable after
//!   the call.
//!
//! Array elements are stored as occam stores them: INT 4 bytes (`i32`), BOOL and BYTE one byte
//! (BOOL 0 or 1), REAL32/REAL64 IEEE floats.
//!
//! Results come back as `i64`, `f32` or `f64`. Intrinsics never block and never see the node.
//! The occam side declares them in `stdlib/` (for example `REAL64 FUNCTION DSQRT (VAL REAL64 x)`)
//! and codegen calls them directly instead of compiling a body.
//!
//! Other crates provide their own tables (for example `occ_radiosity::intrinsics::INTRINSICS`):
//! an occam program declares their routines with `#PRAGMA EXTERNAL "PROC NAME (...) = 0"`, and the
//! driver hands the code generator an [`IntrinsicSet`] naming every table it may bind. The runtime
//! itself never depends on those crates: this module states the ABI (the kinds below), the other
//! crates state their entries.

mod maths;
pub mod predefine;
pub mod realfmt;
mod strings;

/// The occam kind of one intrinsic parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamKind {
    /// `VAL INT` (also INT64, INT32, INT16 sign-extended).
    ValInt,
    /// `VAL BYTE`.
    ValByte,
    /// `VAL BOOL`.
    ValBool,
    /// `VAL REAL32`.
    ValReal32,
    /// `VAL REAL64`.
    ValReal64,
    /// `VAL []BYTE`: address and length.
    ValBytes,
    /// `[]BYTE` (written): address and length.
    VarBytes,
    /// `VAL []REAL64`: address and length.
    ValReal64s,
    /// `[]REAL64` (written): address and length.
    VarReal64s,
    /// `RESULT INT` or `INT` (written): address of a word.
    ResultInt,
    /// `VAL []INT`: address of `i32` elements and length.
    ValInts,
    /// `[]INT` (written): address of `i32` elements and length.
    VarInts,
    /// `VAL []REAL32`: address and length.
    ValReal32s,
    /// `[]REAL32` (written): address and length.
    VarReal32s,
    /// `VAL []BOOL`: address of one-byte elements (0 or 1) and length.
    ValBools,
    /// `[]BOOL` (written): address of one-byte elements (0 or 1) and length.
    VarBools,
    /// `RESULT REAL32` or `REAL32` (written): address of an `f32`.
    ResultReal32,
    /// `RESULT BOOL` or `BOOL` (written): address of a word the intrinsic sets to 0 or 1.
    ResultBool,
    /// `RESULT REAL64` (written): address of an `f64` (the predefine intrinsics' results only).
    ResultReal64,
}

/// The machine type of one argument or result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MachineType {
    /// A 64-bit integer or pointer.
    I64,
    /// A 32-bit float.
    F32,
    /// A 64-bit float.
    F64,
}

impl ParamKind {
    /// The machine arguments this parameter lowers to.
    pub fn machine(self) -> &'static [MachineType] {
        use MachineType::*;
        match self {
            ParamKind::ValInt
            | ParamKind::ValByte
            | ParamKind::ValBool
            | ParamKind::ResultInt
            | ParamKind::ResultReal32
            | ParamKind::ResultReal64
            | ParamKind::ResultBool => &[I64],
            ParamKind::ValReal32 => &[F32],
            ParamKind::ValReal64 => &[F64],
            ParamKind::ValBytes
            | ParamKind::VarBytes
            | ParamKind::ValReal64s
            | ParamKind::VarReal64s
            | ParamKind::ValInts
            | ParamKind::VarInts
            | ParamKind::ValReal32s
            | ParamKind::VarReal32s
            | ParamKind::ValBools
            | ParamKind::VarBools => &[I64, I64],
        }
    }

    /// Reports whether the intrinsic writes through this parameter (the caller passes a
    /// variable, not a value).
    pub fn is_written(self) -> bool {
        matches!(
            self,
            ParamKind::VarBytes
                | ParamKind::VarInts
                | ParamKind::VarReal32s
                | ParamKind::VarReal64s
                | ParamKind::VarBools
                | ParamKind::ResultInt
                | ParamKind::ResultReal32
                | ParamKind::ResultReal64
                | ParamKind::ResultBool
        )
    }

    /// Reports whether this is an array parameter (address and length).
    pub fn is_array(self) -> bool {
        self.machine().len() == 2
    }

    /// The occam spelling of the parameter kind, for diagnostics (`VAL []REAL32`).
    pub fn occam(self) -> &'static str {
        match self {
            ParamKind::ValInt => "VAL INT",
            ParamKind::ValByte => "VAL BYTE",
            ParamKind::ValBool => "VAL BOOL",
            ParamKind::ValReal32 => "VAL REAL32",
            ParamKind::ValReal64 => "VAL REAL64",
            ParamKind::ValBytes => "VAL []BYTE",
            ParamKind::VarBytes => "[]BYTE",
            ParamKind::ValReal64s => "VAL []REAL64",
            ParamKind::VarReal64s => "[]REAL64",
            ParamKind::ResultInt => "RESULT INT",
            ParamKind::ValInts => "VAL []INT",
            ParamKind::VarInts => "[]INT",
            ParamKind::ValReal32s => "VAL []REAL32",
            ParamKind::VarReal32s => "[]REAL32",
            ParamKind::ValBools => "VAL []BOOL",
            ParamKind::VarBools => "[]BOOL",
            ParamKind::ResultReal32 => "RESULT REAL32",
            ParamKind::ResultBool => "RESULT BOOL",
            ParamKind::ResultReal64 => "RESULT REAL64",
        }
    }
}

impl MachineType {
    /// The occam result types this machine type carries, for diagnostics.
    pub fn occam(self) -> &'static str {
        match self {
            MachineType::I64 => "INT, BYTE or BOOL",
            MachineType::F32 => "REAL32",
            MachineType::F64 => "REAL64",
        }
    }
}

/// One native intrinsic.
#[derive(Clone, Copy, Debug)]
pub struct Intrinsic {
    /// The occam name (a PROC or FUNCTION name).
    pub name: &'static str,
    /// The occam parameters in order.
    pub params: &'static [ParamKind],
    /// The FUNCTION result's machine type, or `None` for a PROC.
    pub result: Option<MachineType>,
    /// The function's address.
    pub addr: *const u8,
}

// SAFETY: only static data and function addresses.
unsafe impl Sync for Intrinsic {}

impl Intrinsic {
    /// The flattened machine parameter list.
    pub fn machine_params(&self) -> Vec<MachineType> {
        self.params
            .iter()
            .flat_map(|p| p.machine())
            .copied()
            .collect()
    }
}

use MachineType::{F32, F64};
use ParamKind::*;

/// A REAL FUNCTION intrinsic.
macro_rules! real_fn {
    ($name:literal, [$($p:expr),*], $r:expr, $f:path) => {
        Intrinsic { name: $name, params: &[$($p),*], result: Some($r), addr: $f as *const u8 }
    };
}

/// The predefined REAL routines the maths library implements (the code generator calls them for
/// the predefines of these names; they are also in [`INTRINSICS`]).
/// `SQRT`.
pub const SQRT: Intrinsic = real_fn!("SQRT", [ValReal32], F32, maths::sqrt32);
/// `DSQRT`.
pub const DSQRT: Intrinsic = real_fn!("DSQRT", [ValReal64], F64, maths::sqrt64);
/// `SCALEB`.
pub const SCALEB: Intrinsic = real_fn!("SCALEB", [ValReal32, ValInt], F32, maths::scaleb32);
/// `DSCALEB`.
pub const DSCALEB: Intrinsic = real_fn!("DSCALEB", [ValReal64, ValInt], F64, maths::scaleb64);
/// `LOGB`.
pub const LOGB: Intrinsic = real_fn!("LOGB", [ValReal32], F32, maths::logb32);
/// `DLOGB`.
pub const DLOGB: Intrinsic = real_fn!("DLOGB", [ValReal64], F64, maths::logb64);
/// `FPINT`.
pub const FPINT: Intrinsic = real_fn!("FPINT", [ValReal32], F32, maths::fpint32);
/// `DFPINT`.
pub const DFPINT: Intrinsic = real_fn!("DFPINT", [ValReal64], F64, maths::fpint64);
/// `NEXTAFTER`.
pub const NEXTAFTER: Intrinsic =
    real_fn!("NEXTAFTER", [ValReal32, ValReal32], F32, maths::nextafter32);
/// `DNEXTAFTER`.
pub const DNEXTAFTER: Intrinsic = real_fn!(
    "DNEXTAFTER",
    [ValReal64, ValReal64],
    F64,
    maths::nextafter64
);

/// Every intrinsic, shared by the compiler (calls) and the runtime (definitions): the REAL
/// predefines SQRT/DSQRT, SCALEB, LOGB, FPINT, NEXTAFTER (and D forms); the Inmos maths library
/// (SIN ... POWER, single and double: results follow the host's libm to within an ulp or two,
/// domain errors give NaN as in the Inmos library); and string conversions.
pub static INTRINSICS: &[Intrinsic] = &[
    SQRT,
    DSQRT,
    SCALEB,
    DSCALEB,
    LOGB,
    DLOGB,
    FPINT,
    DFPINT,
    NEXTAFTER,
    DNEXTAFTER,
    real_fn!("SIN", [ValReal32], F32, maths::sin32),
    real_fn!("DSIN", [ValReal64], F64, maths::sin64),
    real_fn!("COS", [ValReal32], F32, maths::cos32),
    real_fn!("DCOS", [ValReal64], F64, maths::cos64),
    real_fn!("TAN", [ValReal32], F32, maths::tan32),
    real_fn!("DTAN", [ValReal64], F64, maths::tan64),
    real_fn!("ASIN", [ValReal32], F32, maths::asin32),
    real_fn!("DASIN", [ValReal64], F64, maths::asin64),
    real_fn!("ACOS", [ValReal32], F32, maths::acos32),
    real_fn!("DACOS", [ValReal64], F64, maths::acos64),
    real_fn!("ATAN", [ValReal32], F32, maths::atan32),
    real_fn!("DATAN", [ValReal64], F64, maths::atan64),
    real_fn!("ATAN2", [ValReal32, ValReal32], F32, maths::atan2_32),
    real_fn!("DATAN2", [ValReal64, ValReal64], F64, maths::atan2_64),
    real_fn!("SINH", [ValReal32], F32, maths::sinh32),
    real_fn!("DSINH", [ValReal64], F64, maths::sinh64),
    real_fn!("COSH", [ValReal32], F32, maths::cosh32),
    real_fn!("DCOSH", [ValReal64], F64, maths::cosh64),
    real_fn!("TANH", [ValReal32], F32, maths::tanh32),
    real_fn!("DTANH", [ValReal64], F64, maths::tanh64),
    real_fn!("EXP", [ValReal32], F32, maths::exp32),
    real_fn!("DEXP", [ValReal64], F64, maths::exp64),
    real_fn!("ALOG", [ValReal32], F32, maths::ln32),
    real_fn!("DALOG", [ValReal64], F64, maths::ln64),
    real_fn!("ALOG10", [ValReal32], F32, maths::log10_32),
    real_fn!("DALOG10", [ValReal64], F64, maths::log10_64),
    real_fn!("POWER", [ValReal32, ValReal32], F32, maths::pow32),
    real_fn!("DPOWER", [ValReal64, ValReal64], F64, maths::pow64),
    Intrinsic {
        name: "INTTOSTRING",
        params: &[ResultInt, VarBytes, ValInt],
        result: None,
        addr: strings::int_to_string as *const u8,
    },
    Intrinsic {
        name: "REAL64TOSTRING",
        params: &[ResultInt, VarBytes, ValReal64, ValInt, ValInt],
        result: None,
        addr: strings::real64_to_string as *const u8,
    },
    real_fn!("SUM.REAL64", [ValReal64s], F64, strings::sum_real64),
    Intrinsic {
        name: "COURSE.REAL32TOSTRING",
        params: &[ResultInt, VarBytes, ValReal32, ValInt, ValInt],
        result: None,
        addr: realfmt::real32_to_string as *const u8,
    },
    Intrinsic {
        name: "COURSE.REAL64TOSTRING",
        params: &[ResultInt, VarBytes, ValReal64, ValInt, ValInt],
        result: None,
        addr: realfmt::real64_to_string as *const u8,
    },
];

/// Finds an intrinsic of the runtime's own table by occam name.
pub fn intrinsic(name: &str) -> Option<&'static Intrinsic> {
    INTRINSICS.iter().find(|i| i.name == name)
}

/// The intrinsic tables a program may bind: always the runtime's [`INTRINSICS`], then the tables
/// added with [`IntrinsicSet::with`], in order. When two tables define the same name the first
/// one wins.
#[derive(Clone, Debug)]
pub struct IntrinsicSet {
    tables: Vec<&'static [Intrinsic]>,
}

impl Default for IntrinsicSet {
    fn default() -> Self {
        IntrinsicSet {
            tables: vec![INTRINSICS],
        }
    }
}

impl IntrinsicSet {
    /// The runtime's own table only.
    pub fn new() -> Self {
        IntrinsicSet::default()
    }

    /// Adds another crate's table (a table already in the set is not added twice).
    pub fn with(mut self, table: &'static [Intrinsic]) -> Self {
        if !self.tables.iter().any(|t| std::ptr::eq(*t, table)) {
            self.tables.push(table);
        }
        self
    }

    /// Finds an intrinsic by occam name in the first table that has it.
    pub fn find(&self, name: &str) -> Option<&'static Intrinsic> {
        self.tables
            .iter()
            .find_map(|t| t.iter().find(|i| i.name == name))
    }

    /// Every intrinsic of the set, each name once (the first table's entry).
    pub fn iter(&self) -> impl Iterator<Item = &'static Intrinsic> + '_ {
        let mut seen = std::collections::HashSet::new();
        self.tables
            .iter()
            .flat_map(|t| t.iter())
            .filter(move |i| seen.insert(i.name))
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::abi::Word;

    #[test]
    fn scalar_intrinsics_through_their_addresses() {
        let e = intrinsic("DSQRT").expect("DSQRT");
        assert_eq!(e.machine_params(), vec![MachineType::F64]);
        // SAFETY: the table says DSQRT is extern "C" fn(f64) -> f64.
        let f: extern "C" fn(f64) -> f64 = unsafe { std::mem::transmute(e.addr) };
        assert_eq!(f(2.25), 1.5);
        let s = intrinsic("SQRT").expect("SQRT");
        // SAFETY: the table says SQRT is extern "C" fn(f32) -> f32.
        let g: extern "C" fn(f32) -> f32 = unsafe { std::mem::transmute(s.addr) };
        assert_eq!(g(16.0), 4.0);
    }

    #[test]
    fn array_and_result_parameters() {
        let e = intrinsic("INTTOSTRING").expect("INTTOSTRING");
        assert_eq!(e.machine_params().len(), 4);
        type F = unsafe extern "C" fn(*mut Word, *mut u8, Word, Word);
        // SAFETY: the table gives this signature.
        let f: F = unsafe { std::mem::transmute(e.addr) };
        let mut len: Word = 0;
        let mut buf = [0u8; 8];
        // SAFETY: valid pointers.
        unsafe { f(&mut len, buf.as_mut_ptr(), 8, -1234) };
        assert_eq!(&buf[..len as usize], b"-1234");
        // SAFETY: valid pointers.
        unsafe { f(&mut len, buf.as_mut_ptr(), 2, 1234) };
        assert_eq!(len, -1);
        let s = intrinsic("SUM.REAL64").expect("SUM.REAL64");
        // SAFETY: the table gives this signature.
        let g: unsafe extern "C" fn(*const f64, Word) -> f64 =
            unsafe { std::mem::transmute(s.addr) };
        let xs = [1.0, 2.5, 3.5];
        // SAFETY: valid slice.
        assert_eq!(unsafe { g(xs.as_ptr(), 3) }, 7.0);
    }

    #[test]
    fn a_set_binds_extra_tables_and_the_first_name_wins() {
        static EXTRA: &[Intrinsic] = &[
            real_fn!("SQRT", [ValReal64], F64, maths::sqrt64),
            real_fn!("EXTRA.SQRT", [ValReal64], F64, maths::sqrt64),
        ];
        let set = IntrinsicSet::new().with(EXTRA).with(EXTRA);
        assert_eq!(set.find("SQRT").map(|i| i.params), Some(&[ValReal32][..]));
        assert!(set.find("EXTRA.SQRT").is_some());
        assert!(set.find("NOT.THERE").is_none());
        assert_eq!(set.iter().count(), INTRINSICS.len() + 1);
        assert!(ParamKind::VarReal32s.is_written() && ParamKind::VarReal32s.is_array());
        assert!(!ParamKind::ValBools.is_written() && ParamKind::ValBools.is_array());
        assert_eq!(ParamKind::ResultReal32.machine(), &[MachineType::I64]);
    }

    #[test]
    fn real_formatting() {
        let e = intrinsic("REAL64TOSTRING").expect("REAL64TOSTRING");
        type F = unsafe extern "C" fn(*mut Word, *mut u8, Word, f64, Word, Word);
        // SAFETY: the table gives this signature.
        let f: F = unsafe { std::mem::transmute(e.addr) };
        let mut len: Word = 0;
        let mut buf = [0u8; 32];
        // SAFETY: valid pointers.
        unsafe { f(&mut len, buf.as_mut_ptr(), 32, 2.5, 0, 3) };
        assert_eq!(&buf[..len as usize], b"2.500");
    }
}
