//! Native intrinsics: Rust functions that occam code calls with occam parameters.
//!
//! [`INTRINSICS`] is the one table the compiler and the runtime share. Each entry gives the occam
//! name, the occam parameter kinds in order, the result kind (for FUNCTIONs) and the function's
//! address. The machine signature follows from the kinds ([`ParamKind::machine`]):
//! - `VAL INT`/`BYTE`/`BOOL` pass one `i64` word (BOOL: 0 or 1; BYTE: 0..255);
//! - `VAL REAL32`/`REAL64` pass an `f32`/`f64`;
//! - an array (`VAL []T` or `[]T`) passes two words, the address of element 0 and the element
//!   count;
//! - `RESULT`/`VAR` scalars pass the address of the variable.
//!
//! Results come back as `i64`, `f32` or `f64`. Intrinsics never block and never see the node.
//! The occam side declares them in `stdlib/` (for example `REAL64 FUNCTION DSQRT (VAL REAL64 x)`)
//! and codegen calls them directly instead of compiling a body.

mod maths;
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
    /// `RESULT INT` or `INT` (written): address.
    ResultInt,
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
            ParamKind::ValInt | ParamKind::ValByte | ParamKind::ValBool | ParamKind::ResultInt => {
                &[I64]
            }
            ParamKind::ValReal32 => &[F32],
            ParamKind::ValReal64 => &[F64],
            ParamKind::ValBytes | ParamKind::VarBytes | ParamKind::ValReal64s => &[I64, I64],
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

/// Every intrinsic, shared by the compiler (calls) and the runtime (definitions): the REAL
/// predefines SQRT/DSQRT, SCALEB, LOGB, FPINT, NEXTAFTER (and D forms); the Inmos maths library
/// (SIN ... POWER, single and double: results follow the host's libm to within an ulp or two,
/// domain errors give NaN as in the Inmos library); and string conversions.
pub static INTRINSICS: &[Intrinsic] = &[
    real_fn!("SQRT", [ValReal32], F32, maths::sqrt32),
    real_fn!("DSQRT", [ValReal64], F64, maths::sqrt64),
    real_fn!("SCALEB", [ValReal32, ValInt], F32, maths::scaleb32),
    real_fn!("DSCALEB", [ValReal64, ValInt], F64, maths::scaleb64),
    real_fn!("LOGB", [ValReal32], F32, maths::logb32),
    real_fn!("DLOGB", [ValReal64], F64, maths::logb64),
    real_fn!("FPINT", [ValReal32], F32, maths::fpint32),
    real_fn!("DFPINT", [ValReal64], F64, maths::fpint64),
    real_fn!("NEXTAFTER", [ValReal32, ValReal32], F32, maths::nextafter32),
    real_fn!(
        "DNEXTAFTER",
        [ValReal64, ValReal64],
        F64,
        maths::nextafter64
    ),
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
];

/// Finds an intrinsic by occam name.
pub fn intrinsic(name: &str) -> Option<&'static Intrinsic> {
    INTRINSICS.iter().find(|i| i.name == name)
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
