//! The occam predefined routines, as a table of signatures.
//!
//! These are in scope in every program, outside the outermost declaration, so a program may
//! redeclare any of them. The table gives what the checker needs (kind, parameter modes and types,
//! result types) and each routine's [`PredefinedId`], on which the code generator matches.
//! Signatures follow the occam 2.1 Reference Manual appendix "Predefined routines" and KRoC's
//! `forall` library.

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

/// Which predefined routine a [`Predefined`] is: the code generator matches on it (exhaustively),
/// so a routine added to [`PREDEFINED`] must be given a lowering.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PredefinedId {
    /// `LONGADD`.
    LongAdd,
    /// `LONGSUB`.
    LongSub,
    /// `ASHIFTLEFT`.
    AShiftLeft,
    /// `ASHIFTRIGHT`.
    AShiftRight,
    /// `ROTATELEFT`.
    RotateLeft,
    /// `ROTATERIGHT`.
    RotateRight,
    /// `LONGSUM`.
    LongSum,
    /// `LONGDIFF`.
    LongDiff,
    /// `LONGPROD`.
    LongProd,
    /// `LONGDIV`.
    LongDiv,
    /// `SHIFTLEFT`.
    ShiftLeft,
    /// `SHIFTRIGHT`.
    ShiftRight,
    /// `NORMALISE`.
    Normalise,
    /// `FRACMUL`.
    FracMul,
    /// `UNPACKSN`.
    UnpackSn,
    /// `ROUNDSN`.
    RoundSn,
    /// `ABS`.
    Abs,
    /// `DABS`.
    DAbs,
    /// `SQRT`.
    Sqrt,
    /// `DSQRT`.
    DSqrt,
    /// `ISNAN`.
    IsNan,
    /// `DISNAN`.
    DIsNan,
    /// `NOTFINITE`.
    NotFinite,
    /// `DNOTFINITE`.
    DNotFinite,
    /// `ORDERED`.
    Ordered,
    /// `DORDERED`.
    DOrdered,
    /// `MULBY2`.
    MulBy2,
    /// `DMULBY2`.
    DMulBy2,
    /// `DIVBY2`.
    DivBy2,
    /// `DDIVBY2`.
    DDivBy2,
    /// `LOGB`.
    LogB,
    /// `DLOGB`.
    DLogB,
    /// `SCALEB`.
    ScaleB,
    /// `DSCALEB`.
    DScaleB,
    /// `COPYSIGN`.
    CopySign,
    /// `DCOPYSIGN`.
    DCopySign,
    /// `NEXTAFTER`.
    NextAfter,
    /// `DNEXTAFTER`.
    DNextAfter,
    /// `MINUSX`.
    MinusX,
    /// `DMINUSX`.
    DMinusX,
    /// `FLOATING.UNPACK`.
    FloatingUnpack,
    /// `DFLOATING.UNPACK`.
    DFloatingUnpack,
    /// `ARGUMENT.REDUCE`.
    ArgumentReduce,
    /// `DARGUMENT.REDUCE`.
    DArgumentReduce,
    /// `REAL32OP`.
    Real32Op,
    /// `REAL64OP`.
    Real64Op,
    /// `IEEE32OP`.
    Ieee32Op,
    /// `IEEE64OP`.
    Ieee64Op,
    /// `REAL32REM`.
    Real32Rem,
    /// `REAL64REM`.
    Real64Rem,
    /// `IEEE32REM`.
    Ieee32Rem,
    /// `IEEE64REM`.
    Ieee64Rem,
    /// `REAL32EQ`.
    Real32Eq,
    /// `REAL64EQ`.
    Real64Eq,
    /// `REAL32GT`.
    Real32Gt,
    /// `REAL64GT`.
    Real64Gt,
    /// `IEEECOMPARE`.
    IeeeCompare,
    /// `DIEEECOMPARE`.
    DIeeeCompare,
    /// `FPINT`.
    FpInt,
    /// `DFPINT`.
    DFpInt,
    /// `BITCOUNT`.
    BitCount,
    /// `BITREVWORD`.
    BitRevWord,
    /// `BITREVNBITS`.
    BitRevNBits,
    /// `CRCWORD`.
    CrcWord,
    /// `CRCBYTE`.
    CrcByte,
    /// `ASSERT`.
    Assert,
    /// `RESCHEDULE`.
    Reschedule,
    /// `CAUSEERROR`.
    CauseError,
    /// `MOVE2D`.
    Move2D,
    /// `DRAW2D`.
    Draw2D,
    /// `CLIP2D`.
    Clip2D,
}

/// A predefined routine's signature.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Predefined {
    /// Which routine it is.
    pub id: PredefinedId,
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
use PredefinedId as Id;
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
    id: PredefinedId,
    name: &'static str,
    results: &'static [Prim],
    params: &'static [(bool, PType)],
) -> Predefined {
    Predefined {
        id,
        name,
        results,
        params,
    }
}

/// Every predefined routine.
pub const PREDEFINED: &[Predefined] = &[
    // Integer and long arithmetic.
    f(Id::LongAdd, "LONGADD", &[I], I3),
    f(Id::LongSub, "LONGSUB", &[I], I3),
    f(Id::AShiftLeft, "ASHIFTLEFT", &[I], I2),
    f(Id::AShiftRight, "ASHIFTRIGHT", &[I], I2),
    f(Id::RotateLeft, "ROTATELEFT", &[I], I2),
    f(Id::RotateRight, "ROTATERIGHT", &[I], I2),
    f(Id::LongSum, "LONGSUM", &[I, I], I3),
    f(Id::LongDiff, "LONGDIFF", &[I, I], I3),
    f(Id::LongProd, "LONGPROD", &[I, I], I3),
    f(Id::LongDiv, "LONGDIV", &[I, I], I3),
    f(Id::ShiftLeft, "SHIFTLEFT", &[I, I], I3),
    f(Id::ShiftRight, "SHIFTRIGHT", &[I, I], I3),
    f(Id::Normalise, "NORMALISE", &[I, I, I], I2),
    f(Id::FracMul, "FRACMUL", &[I], I2),
    f(Id::UnpackSn, "UNPACKSN", &[I, I, I], I1),
    f(Id::RoundSn, "ROUNDSN", &[I], I3),
    // REAL32 / REAL64 arithmetic support.
    f(Id::Abs, "ABS", &[R], R1),
    f(Id::DAbs, "DABS", &[D], D1),
    f(Id::Sqrt, "SQRT", &[R], R1),
    f(Id::DSqrt, "DSQRT", &[D], D1),
    f(Id::IsNan, "ISNAN", &[B], R1),
    f(Id::DIsNan, "DISNAN", &[B], D1),
    f(Id::NotFinite, "NOTFINITE", &[B], R1),
    f(Id::DNotFinite, "DNOTFINITE", &[B], D1),
    f(Id::Ordered, "ORDERED", &[B], R2),
    f(Id::DOrdered, "DORDERED", &[B], D2),
    f(Id::MulBy2, "MULBY2", &[R], R1),
    f(Id::DMulBy2, "DMULBY2", &[D], D1),
    f(Id::DivBy2, "DIVBY2", &[R], R1),
    f(Id::DDivBy2, "DDIVBY2", &[D], D1),
    f(Id::LogB, "LOGB", &[R], R1),
    f(Id::DLogB, "DLOGB", &[D], D1),
    f(Id::ScaleB, "SCALEB", &[R], RI),
    f(Id::DScaleB, "DSCALEB", &[D], DI),
    f(Id::CopySign, "COPYSIGN", &[R], R2),
    f(Id::DCopySign, "DCOPYSIGN", &[D], D2),
    f(Id::NextAfter, "NEXTAFTER", &[R], R2),
    f(Id::DNextAfter, "DNEXTAFTER", &[D], D2),
    f(Id::MinusX, "MINUSX", &[R], R1),
    f(Id::DMinusX, "DMINUSX", &[D], D1),
    f(Id::FloatingUnpack, "FLOATING.UNPACK", &[I, R], R1),
    f(Id::DFloatingUnpack, "DFLOATING.UNPACK", &[I, D], D1),
    f(Id::ArgumentReduce, "ARGUMENT.REDUCE", &[B, I32, R], R3),
    f(Id::DArgumentReduce, "DARGUMENT.REDUCE", &[B, I32, D], D3),
    f(
        Id::Real32Op,
        "REAL32OP",
        &[R],
        &[(V, P(R)), (V, P(I)), (V, P(R))],
    ),
    f(
        Id::Real64Op,
        "REAL64OP",
        &[D],
        &[(V, P(D)), (V, P(I)), (V, P(D))],
    ),
    f(
        Id::Ieee32Op,
        "IEEE32OP",
        &[B, R],
        &[(V, P(R)), (V, P(I)), (V, P(I)), (V, P(R))],
    ),
    f(
        Id::Ieee64Op,
        "IEEE64OP",
        &[B, D],
        &[(V, P(D)), (V, P(I)), (V, P(I)), (V, P(D))],
    ),
    f(Id::Real32Rem, "REAL32REM", &[R], R2),
    f(Id::Real64Rem, "REAL64REM", &[D], D2),
    f(Id::Ieee32Rem, "IEEE32REM", &[B, R], R2),
    f(Id::Ieee64Rem, "IEEE64REM", &[B, D], D2),
    f(Id::Real32Eq, "REAL32EQ", &[B], R2),
    f(Id::Real64Eq, "REAL64EQ", &[B], D2),
    f(Id::Real32Gt, "REAL32GT", &[B], R2),
    f(Id::Real64Gt, "REAL64GT", &[B], D2),
    f(Id::IeeeCompare, "IEEECOMPARE", &[I], R2),
    f(Id::DIeeeCompare, "DIEEECOMPARE", &[I], D2),
    f(Id::FpInt, "FPINT", &[R], R1),
    f(Id::DFpInt, "DFPINT", &[D], D1),
    // Bit manipulation and CRCs.
    f(Id::BitCount, "BITCOUNT", &[I], I2),
    f(Id::BitRevWord, "BITREVWORD", &[I], I1),
    f(Id::BitRevNBits, "BITREVNBITS", &[I], I2),
    f(Id::CrcWord, "CRCWORD", &[I], I3),
    f(Id::CrcByte, "CRCBYTE", &[I], I3),
    // Processes.
    f(Id::Assert, "ASSERT", &[], &[(V, P(B))]),
    f(Id::Reschedule, "RESCHEDULE", &[], &[]),
    f(Id::CauseError, "CAUSEERROR", &[], &[]),
    // 2D block moves (transputer `move2d` family), used by graphics code.
    f(
        Id::Move2D,
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
        Id::Draw2D,
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
        Id::Clip2D,
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
        for (i, p) in PREDEFINED.iter().enumerate() {
            assert!(
                PREDEFINED[..i].iter().all(|o| o.id != p.id),
                "{} shares its id",
                p.name
            );
        }
    }
}
