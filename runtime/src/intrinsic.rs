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

use crate::abi::Word;

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

use ParamKind::*;

/// Every intrinsic, shared by the compiler (calls) and the runtime (definitions).
pub static INTRINSICS: &[Intrinsic] = &[
    Intrinsic {
        name: "SQRT",
        params: &[ValReal32],
        result: Some(MachineType::F32),
        addr: sqrt32 as *const u8,
    },
    Intrinsic {
        name: "DSQRT",
        params: &[ValReal64],
        result: Some(MachineType::F64),
        addr: sqrt64 as *const u8,
    },
    Intrinsic {
        name: "DSIN",
        params: &[ValReal64],
        result: Some(MachineType::F64),
        addr: sin64 as *const u8,
    },
    Intrinsic {
        name: "DCOS",
        params: &[ValReal64],
        result: Some(MachineType::F64),
        addr: cos64 as *const u8,
    },
    Intrinsic {
        name: "DEXP",
        params: &[ValReal64],
        result: Some(MachineType::F64),
        addr: exp64 as *const u8,
    },
    Intrinsic {
        name: "DALOG",
        params: &[ValReal64],
        result: Some(MachineType::F64),
        addr: ln64 as *const u8,
    },
    Intrinsic {
        name: "DPOWER",
        params: &[ValReal64, ValReal64],
        result: Some(MachineType::F64),
        addr: pow64 as *const u8,
    },
    Intrinsic {
        name: "DATAN2",
        params: &[ValReal64, ValReal64],
        result: Some(MachineType::F64),
        addr: atan2_64 as *const u8,
    },
    Intrinsic {
        name: "INTTOSTRING",
        params: &[ResultInt, VarBytes, ValInt],
        result: None,
        addr: int_to_string as *const u8,
    },
    Intrinsic {
        name: "REAL64TOSTRING",
        params: &[ResultInt, VarBytes, ValReal64, ValInt, ValInt],
        result: None,
        addr: real64_to_string as *const u8,
    },
    Intrinsic {
        name: "SUM.REAL64",
        params: &[ValReal64s],
        result: Some(MachineType::F64),
        addr: sum_real64 as *const u8,
    },
];

/// Finds an intrinsic by occam name.
pub fn intrinsic(name: &str) -> Option<&'static Intrinsic> {
    INTRINSICS.iter().find(|i| i.name == name)
}

extern "C" fn sqrt32(x: f32) -> f32 {
    x.sqrt()
}

extern "C" fn sqrt64(x: f64) -> f64 {
    x.sqrt()
}

extern "C" fn sin64(x: f64) -> f64 {
    x.sin()
}

extern "C" fn cos64(x: f64) -> f64 {
    x.cos()
}

extern "C" fn exp64(x: f64) -> f64 {
    x.exp()
}

extern "C" fn ln64(x: f64) -> f64 {
    x.ln()
}

extern "C" fn pow64(x: f64, y: f64) -> f64 {
    x.powf(y)
}

extern "C" fn atan2_64(y: f64, x: f64) -> f64 {
    y.atan2(x)
}

/// Writes `text` into the byte array (`ptr`, `cap`) and its length into `*len`; if it does not
/// fit, `*len` is -1 and the array is untouched.
///
/// # Safety
/// `len` is a valid INT; `ptr` valid for `cap` bytes.
unsafe fn put_string(len: *mut Word, ptr: *mut u8, cap: Word, text: &str) {
    let n = text.len();
    // SAFETY: caller contract.
    unsafe {
        if n as Word > cap {
            *len = -1;
            return;
        }
        std::ptr::copy_nonoverlapping(text.as_ptr(), ptr, n);
        *len = n as Word;
    }
}

/// `INTTOSTRING (RESULT INT len, []BYTE string, VAL INT n)`: decimal digits of `n`.
///
/// # Safety
/// As for [`put_string`].
unsafe extern "C" fn int_to_string(len: *mut Word, ptr: *mut u8, cap: Word, n: Word) {
    // SAFETY: forwarded contract.
    unsafe { put_string(len, ptr, cap, &n.to_string()) }
}

/// `REAL64TOSTRING (RESULT INT len, []BYTE string, VAL REAL64 x, VAL INT Ip, Dp)`: with
/// `Ip = Dp = 0` the shortest decimal that reads back as `x`; otherwise fixed point with `Dp`
/// decimals (`Ip` is not used for padding).
///
/// # Safety
/// As for [`put_string`].
unsafe extern "C" fn real64_to_string(
    len: *mut Word,
    ptr: *mut u8,
    cap: Word,
    x: f64,
    ip: Word,
    dp: Word,
) {
    let text = if ip == 0 && dp == 0 {
        format!("{x:?}")
    } else {
        format!("{x:.prec$}", prec = dp.clamp(0, 30) as usize)
    };
    // SAFETY: forwarded contract.
    unsafe { put_string(len, ptr, cap, &text) }
}

/// `REAL64 FUNCTION SUM.REAL64 (VAL []REAL64 xs)`: the sum of the elements.
///
/// # Safety
/// `ptr` valid for `n` REAL64s.
unsafe extern "C" fn sum_real64(ptr: *const f64, n: Word) -> f64 {
    if n <= 0 {
        return 0.0;
    }
    // SAFETY: caller contract.
    unsafe { std::slice::from_raw_parts(ptr, n as usize) }
        .iter()
        .sum()
}

#[cfg(test)]
mod test {
    use super::*;

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
