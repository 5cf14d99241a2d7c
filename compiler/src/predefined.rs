//! The occam predefined routines, as a table of signatures.
//!
//! These are in scope in every program, outside the outermost declaration, so a program may
//! redeclare any of them. The table gives what the checker needs (kind, parameter modes and types,
//! result types); the code generator implements each by name. Signatures follow the occam 2.1
//! Reference Manual appendix "Predefined routines" and KRoC's `forall` library.

use crate::types::{Prim, Type};

/// A parameter type in a signature.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PType {
    /// A primitive.
    P(Prim),
    /// An open array `[]T`.
    Open(Prim),
    /// A two-dimensional open array `[][]T`.
    Open2(Prim),
}

impl PType {
    /// Converts to a checker [`Type`].
    pub fn to_type(self) -> Type {
        match self {
            PType::P(p) => Type::Prim(p),
            PType::Open(p) => Type::array(None, Type::Prim(p)),
            PType::Open2(p) => Type::array(None, Type::array(None, Type::Prim(p))),
        }
    }
}

/// A predefined routine's signature.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Predefined {
    /// The name as occam spells it.
    pub name: &'static str,
    /// The result types; empty for a PROC.
    pub results: &'static [Prim],
    /// The parameters: `true` when passed by reference (PROCs only), and the type.
    pub params: &'static [(bool, PType)],
}

impl Predefined {
    /// Reports whether this is a PROC (no results) rather than a FUNCTION.
    pub fn is_proc(&self) -> bool {
        self.results.is_empty()
    }
}

use PType::{Open2, P};
use Prim::{Bool as B, Byte as Y, Int as I, Int32 as I32, Real32 as R, Real64 as D};

const V: bool = false;
const I1: &[(bool, PType)] = &[(V, P(I))];
const I2: &[(bool, PType)] = &[(V, P(I)), (V, P(I))];
const I3: &[(bool, PType)] = &[(V, P(I)), (V, P(I)), (V, P(I))];
const R1: &[(bool, PType)] = &[(V, P(R))];
const R2: &[(bool, PType)] = &[(V, P(R)), (V, P(R))];
const R3: &[(bool, PType)] = &[(V, P(R)), (V, P(R)), (V, P(R))];
const D1: &[(bool, PType)] = &[(V, P(D))];
const D2: &[(bool, PType)] = &[(V, P(D)), (V, P(D))];
const D3: &[(bool, PType)] = &[(V, P(D)), (V, P(D)), (V, P(D))];
const RI: &[(bool, PType)] = &[(V, P(R)), (V, P(I))];
const DI: &[(bool, PType)] = &[(V, P(D)), (V, P(I))];

const fn f(
    name: &'static str,
    results: &'static [Prim],
    params: &'static [(bool, PType)],
) -> Predefined {
    Predefined {
        name,
        results,
        params,
    }
}

/// Every predefined routine.
pub const PREDEFINED: &[Predefined] = &[
    // Integer and long arithmetic.
    f("LONGADD", &[I], I3),
    f("LONGSUB", &[I], I3),
    f("ASHIFTLEFT", &[I], I2),
    f("ASHIFTRIGHT", &[I], I2),
    f("ROTATELEFT", &[I], I2),
    f("ROTATERIGHT", &[I], I2),
    f("LONGSUM", &[I, I], I3),
    f("LONGDIFF", &[I, I], I3),
    f("LONGPROD", &[I, I], I3),
    f("LONGDIV", &[I, I], I3),
    f("SHIFTLEFT", &[I, I], I3),
    f("SHIFTRIGHT", &[I, I], I3),
    f("NORMALISE", &[I, I, I], I2),
    f("FRACMUL", &[I], I2),
    f("UNPACKSN", &[I, I, I], I1),
    f("ROUNDSN", &[I], I3),
    // REAL32 / REAL64 arithmetic support.
    f("ABS", &[R], R1),
    f("DABS", &[D], D1),
    f("SQRT", &[R], R1),
    f("DSQRT", &[D], D1),
    f("ISNAN", &[B], R1),
    f("DISNAN", &[B], D1),
    f("NOTFINITE", &[B], R1),
    f("DNOTFINITE", &[B], D1),
    f("ORDERED", &[B], R2),
    f("DORDERED", &[B], D2),
    f("MULBY2", &[R], R1),
    f("DMULBY2", &[D], D1),
    f("DIVBY2", &[R], R1),
    f("DDIVBY2", &[D], D1),
    f("LOGB", &[R], R1),
    f("DLOGB", &[D], D1),
    f("SCALEB", &[R], RI),
    f("DSCALEB", &[D], DI),
    f("COPYSIGN", &[R], R2),
    f("DCOPYSIGN", &[D], D2),
    f("NEXTAFTER", &[R], R2),
    f("DNEXTAFTER", &[D], D2),
    f("MINUSX", &[R], R1),
    f("DMINUSX", &[D], D1),
    f("FLOATING.UNPACK", &[I, R], R1),
    f("DFLOATING.UNPACK", &[I, D], D1),
    f("ARGUMENT.REDUCE", &[B, I32, R], R3),
    f("DARGUMENT.REDUCE", &[B, I32, D], D3),
    f("REAL32OP", &[R], &[(V, P(R)), (V, P(I)), (V, P(R))]),
    f("REAL64OP", &[D], &[(V, P(D)), (V, P(I)), (V, P(D))]),
    f(
        "IEEE32OP",
        &[B, R],
        &[(V, P(R)), (V, P(I)), (V, P(I)), (V, P(R))],
    ),
    f(
        "IEEE64OP",
        &[B, D],
        &[(V, P(D)), (V, P(I)), (V, P(I)), (V, P(D))],
    ),
    f("REAL32REM", &[R], R2),
    f("REAL64REM", &[D], D2),
    f("IEEE32REM", &[B, R], R2),
    f("IEEE64REM", &[B, D], D2),
    f("REAL32EQ", &[B], R2),
    f("REAL64EQ", &[B], D2),
    f("REAL32GT", &[B], R2),
    f("REAL64GT", &[B], D2),
    f("IEEECOMPARE", &[I], R2),
    f("DIEEECOMPARE", &[I], D2),
    f("FPINT", &[R], R1),
    f("DFPINT", &[D], D1),
    // Bit manipulation and CRCs.
    f("BITCOUNT", &[I], I2),
    f("BITREVWORD", &[I], I1),
    f("BITREVNBITS", &[I], I2),
    f("CRCWORD", &[I], I3),
    f("CRCBYTE", &[I], I3),
    // Processes.
    f("ASSERT", &[], &[(V, P(B))]),
    f("RESCHEDULE", &[], &[]),
    f("CAUSEERROR", &[], &[]),
    // 2D block moves (transputer `move2d` family), used by graphics code.
    f(
        "MOVE2D",
        &[],
        &[
            (V, Open2(Y)),
            (V, P(I)),
            (V, P(I)),
            (true, Open2(Y)),
            (V, P(I)),
            (V, P(I)),
            (V, P(I)),
            (V, P(I)),
        ],
    ),
    f(
        "DRAW2D",
        &[],
        &[
            (V, Open2(Y)),
            (V, P(I)),
            (V, P(I)),
            (true, Open2(Y)),
            (V, P(I)),
            (V, P(I)),
            (V, P(I)),
            (V, P(I)),
        ],
    ),
    f(
        "CLIP2D",
        &[],
        &[
            (V, Open2(Y)),
            (V, P(I)),
            (V, P(I)),
            (true, Open2(Y)),
            (V, P(I)),
            (V, P(I)),
            (V, P(I)),
            (V, P(I)),
        ],
    ),
];

/// Looks a predefined routine up by name.
pub fn lookup(name: &str) -> Option<&'static Predefined> {
    PREDEFINED.iter().find(|p| p.name == name)
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn every_name_in_the_brief_is_present_once() {
        let names = "LONGADD LONGSUB ASHIFTLEFT ASHIFTRIGHT ROTATELEFT ROTATERIGHT LONGSUM LONGDIFF \
            LONGPROD LONGDIV SHIFTLEFT SHIFTRIGHT NORMALISE FRACMUL UNPACKSN ROUNDSN ABS DABS SQRT \
            DSQRT ISNAN DISNAN NOTFINITE DNOTFINITE ORDERED DORDERED MULBY2 DMULBY2 DIVBY2 DDIVBY2 \
            LOGB DLOGB SCALEB DSCALEB COPYSIGN DCOPYSIGN NEXTAFTER DNEXTAFTER MINUSX DMINUSX \
            FLOATING.UNPACK DFLOATING.UNPACK ARGUMENT.REDUCE DARGUMENT.REDUCE REAL32OP REAL64OP \
            IEEE32OP IEEE64OP REAL32REM REAL64REM REAL32EQ REAL64EQ REAL32GT REAL64GT IEEECOMPARE \
            DIEEECOMPARE FPINT DFPINT BITCOUNT BITREVWORD BITREVNBITS CRCWORD CRCBYTE ASSERT RESCHEDULE";
        for name in names.split_whitespace() {
            assert_eq!(
                PREDEFINED.iter().filter(|p| p.name == name).count(),
                1,
                "{name}"
            );
        }
    }

    #[test]
    fn signatures_match_the_reference_manual() {
        let p = lookup("NORMALISE").unwrap();
        assert_eq!((p.results.len(), p.params.len()), (3, 2));
        let p = lookup("ARGUMENT.REDUCE").unwrap();
        assert_eq!(p.results, &[Prim::Bool, Prim::Int32, Prim::Real32]);
        assert!(lookup("ASSERT").unwrap().is_proc());
        assert_eq!(lookup("SCALEB").unwrap().params[1].1, PType::P(Prim::Int));
        assert!(lookup("out.string").is_none());
    }
}
