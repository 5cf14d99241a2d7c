//! occam 2.1 types and their layout on a 32-bit transputer.
//!
//! A [`Type`] is a value-level description: primitive types, arrays (sized or open `[]T`), named
//! types (`DATA TYPE`, `RECORD`, `PACKED RECORD`, stored in a [`TypeTable`]), channels with their
//! protocol and direction, `TIMER` and `PORT`. Named types are distinct from what they name (name
//! equivalence, as occ21 does): a `DATA TYPE METRES IS INT:` value is not an `INT`.
//!
//! Layout follows the T800: `INT` is 32 bits, words are 4 bytes, `BYTESIN` and `OFFSETOF` are in
//! bytes. Unpacked records pad each field to its natural alignment (at most a word); packed records
//! have no padding.

mod layout;
#[cfg(test)]
mod test;

pub use layout::{LayoutError, align_of, bytes_in, offset_of};

use crate::entity::PrimaryMap;
use crate::entity_ref;

entity_ref!(
    /// A named type (`DATA TYPE` or `RECORD`) in a [`TypeTable`].
    TypeDefId
);
entity_ref!(
    /// A named `PROTOCOL` in a [`TypeTable`].
    ProtocolId
);

/// The primitive data types.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Prim {
    /// `BOOL`: TRUE or FALSE, one byte.
    Bool,
    /// `BYTE`: unsigned 0..255.
    Byte,
    /// `INT`: the word, 32 bits on the T800.
    Int,
    /// `INT16`.
    Int16,
    /// `INT32`: 32 bits, but a different type from `INT`.
    Int32,
    /// `INT64`.
    Int64,
    /// `REAL32`: IEEE single.
    Real32,
    /// `REAL64`: IEEE double.
    Real64,
}

impl Prim {
    /// Every primitive type, in declaration order.
    pub const ALL: [Prim; 8] = [
        Prim::Bool,
        Prim::Byte,
        Prim::Int,
        Prim::Int16,
        Prim::Int32,
        Prim::Int64,
        Prim::Real32,
        Prim::Real64,
    ];

    /// Returns the occam keyword for this type.
    pub fn name(self) -> &'static str {
        match self {
            Prim::Bool => "BOOL",
            Prim::Byte => "BYTE",
            Prim::Int => "INT",
            Prim::Int16 => "INT16",
            Prim::Int32 => "INT32",
            Prim::Int64 => "INT64",
            Prim::Real32 => "REAL32",
            Prim::Real64 => "REAL64",
        }
    }

    /// Looks a primitive type up by its keyword.
    pub fn from_name(name: &str) -> Option<Prim> {
        Prim::ALL.into_iter().find(|p| p.name() == name)
    }

    /// Returns the size in bytes.
    pub fn bytes(self) -> u32 {
        match self {
            Prim::Bool | Prim::Byte => 1,
            Prim::Int16 => 2,
            Prim::Int | Prim::Int32 | Prim::Real32 => 4,
            Prim::Int64 | Prim::Real64 => 8,
        }
    }

    /// Returns the width in bits.
    pub fn bits(self) -> u32 {
        self.bytes() * 8
    }

    /// Reports whether this is BYTE or one of the INT types (the types with integer arithmetic).
    pub fn is_integer(self) -> bool {
        matches!(
            self,
            Prim::Byte | Prim::Int | Prim::Int16 | Prim::Int32 | Prim::Int64
        )
    }

    /// Reports whether this is one of the INT types (BYTE excluded).
    pub fn is_signed_integer(self) -> bool {
        self.is_integer() && self != Prim::Byte
    }

    /// Reports whether this is REAL32 or REAL64.
    pub fn is_real(self) -> bool {
        matches!(self, Prim::Real32 | Prim::Real64)
    }

    /// Reports whether arithmetic operators (`+ - * / \`) apply.
    pub fn is_numeric(self) -> bool {
        self.is_integer() || self.is_real()
    }

    /// Returns the inclusive value range of an integer type, or `None` for BOOL and reals.
    pub fn int_range(self) -> Option<(i64, i64)> {
        match self {
            Prim::Byte => Some((0, 255)),
            Prim::Int16 => Some((i16::MIN.into(), i16::MAX.into())),
            Prim::Int | Prim::Int32 => Some((i32::MIN.into(), i32::MAX.into())),
            Prim::Int64 => Some((i64::MIN, i64::MAX)),
            _ => None,
        }
    }
}

/// Which way a channel may be used where it is visible.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// No specifier: input and output are both allowed.
    Both,
    /// `c?`: input only.
    Input,
    /// `c!`: output only.
    Output,
}

/// The protocol a channel carries.
#[derive(Debug, Clone, PartialEq)]
pub enum ChanProtocol {
    /// `CHAN OF ANY`: any sequence of values, sent and received as bytes.
    Any,
    /// `CHAN OF T` with an anonymous simple protocol (a type or a counted array).
    Simple(ProtocolItem),
    /// `CHAN OF P` for a named `PROTOCOL P`.
    Named(ProtocolId),
}

/// One item of a simple or sequential protocol.
#[derive(Debug, Clone, PartialEq)]
pub enum ProtocolItem {
    /// A value of a data type.
    Data(Type),
    /// `count :: []elem`: a count followed by that many elements.
    Counted {
        /// The integer type of the count.
        count: Prim,
        /// The element type of the array.
        elem: Type,
    },
}

/// A named protocol.
#[derive(Debug, Clone, PartialEq)]
pub struct Protocol {
    /// The protocol's name, for messages.
    pub name: String,
    /// What it carries.
    pub kind: ProtocolKind,
}

/// The shapes of a named protocol.
#[derive(Debug, Clone, PartialEq)]
pub enum ProtocolKind {
    /// `PROTOCOL P IS INT; [4]BYTE:` (one item is a simple protocol).
    Sequential(Vec<ProtocolItem>),
    /// `PROTOCOL P CASE tag; INT ... :`.
    Tagged(Vec<Tag>),
    /// A protocol whose declaration had errors; anything goes, to avoid cascades.
    Unknown,
}

/// A tag of a tagged protocol and the items that follow it.
#[derive(Debug, Clone, PartialEq)]
pub struct Tag {
    /// The tag's name.
    pub name: String,
    /// The items sent after the tag (empty for a bare tag).
    pub items: Vec<ProtocolItem>,
}

/// A named data type.
#[derive(Debug, Clone, PartialEq)]
pub struct TypeDef {
    /// The type's name, for messages.
    pub name: String,
    /// What it is defined as.
    pub kind: TypeDefKind,
}

/// The two kinds of named data type.
#[derive(Debug, Clone, PartialEq)]
pub enum TypeDefKind {
    /// `DATA TYPE NAME IS T:`.
    Alias(Type),
    /// `DATA TYPE NAME [PACKED] RECORD` with its fields in order.
    Record {
        /// Whether the record is `PACKED` (no padding).
        packed: bool,
        /// The fields: name and type.
        fields: Vec<(String, Type)>,
    },
}

/// An occam type.
#[derive(Debug, Clone, PartialEq)]
pub enum Type {
    /// A primitive data type.
    Prim(Prim),
    /// `[n]T` (`Some(n)`) or the open array `[]T` (`None`).
    Array(Option<u32>, Box<Type>),
    /// A `DATA TYPE` or `RECORD`.
    Named(TypeDefId),
    /// `CHAN OF P`, with the direction it may be used in here.
    Chan(Box<ChanProtocol>, Direction),
    /// `TIMER`.
    Timer,
    /// `PORT OF T`.
    Port(Box<Type>),
    /// The type of something that already had an error: compatible with everything, so that one
    /// mistake gives one message.
    Error,
}

impl Type {
    /// Shorthand for `Type::Prim(Prim::Int)`.
    pub const INT: Type = Type::Prim(Prim::Int);
    /// Shorthand for `Type::Prim(Prim::Bool)`.
    pub const BOOL: Type = Type::Prim(Prim::Bool);
    /// Shorthand for `Type::Prim(Prim::Byte)`.
    pub const BYTE: Type = Type::Prim(Prim::Byte);

    /// Builds `[n]elem` or `[]elem`.
    pub fn array(len: Option<u32>, elem: Type) -> Type {
        Type::Array(len, Box::new(elem))
    }

    /// Returns the element type of an array, or `None`.
    pub fn elem(&self) -> Option<&Type> {
        match self {
            Type::Array(_, e) => Some(e),
            _ => None,
        }
    }

    /// Reports whether this is a data type (something a variable of which can be declared and
    /// communicated), as opposed to a channel, timer or port.
    pub fn is_data(&self) -> bool {
        match self {
            Type::Prim(_) | Type::Named(_) | Type::Error => true,
            Type::Array(_, e) => e.is_data(),
            _ => false,
        }
    }

    /// Reports whether this type contains an error type anywhere.
    pub fn is_error(&self) -> bool {
        match self {
            Type::Error => true,
            Type::Array(_, e) | Type::Port(e) => e.is_error(),
            _ => false,
        }
    }
}

/// The table of named types and protocols of one program.
#[derive(Debug, Clone, Default)]
pub struct TypeTable {
    /// Every `DATA TYPE` and `RECORD`.
    pub defs: PrimaryMap<TypeDefId, TypeDef>,
    /// Every named `PROTOCOL`.
    pub protocols: PrimaryMap<ProtocolId, Protocol>,
}

impl TypeTable {
    /// Follows `DATA TYPE X IS T` aliases to the representation type (records stay named).
    /// Used for arithmetic and layout; assignment compatibility still uses name equivalence.
    pub fn underlying<'a>(&'a self, ty: &'a Type) -> &'a Type {
        let mut ty = ty;
        for _ in 0..64 {
            match ty {
                Type::Named(id) => match self.defs.get(*id).map(|d| &d.kind) {
                    Some(TypeDefKind::Alias(t)) => ty = t,
                    _ => return ty,
                },
                _ => return ty,
            }
        }
        ty
    }

    /// Returns the primitive representation of `ty`, through aliases, if it has one.
    pub fn prim(&self, ty: &Type) -> Option<Prim> {
        match self.underlying(ty) {
            Type::Prim(p) => Some(*p),
            _ => None,
        }
    }

    /// Returns the fields of a record type, or `None` when `ty` is not a record.
    pub fn record_fields(&self, ty: &Type) -> Option<&[(String, Type)]> {
        match self.underlying(ty) {
            Type::Named(id) => match &self.defs.get(*id)?.kind {
                TypeDefKind::Record { fields, .. } => Some(fields),
                TypeDefKind::Alias(_) => None,
            },
            _ => None,
        }
    }

    /// Renders a type the way occam writes it, for messages.
    pub fn display(&self, ty: &Type) -> String {
        match ty {
            Type::Prim(p) => p.name().to_string(),
            Type::Array(Some(n), e) => format!("[{n}]{}", self.display(e)),
            Type::Array(None, e) => format!("[]{}", self.display(e)),
            Type::Named(id) => self.defs.get(*id).map_or("?".into(), |d| d.name.clone()),
            Type::Chan(p, _) => format!("CHAN OF {}", self.display_protocol(p)),
            Type::Timer => "TIMER".into(),
            Type::Port(e) => format!("PORT OF {}", self.display(e)),
            Type::Error => "<error>".into(),
        }
    }

    /// Renders a channel protocol for messages.
    pub fn display_protocol(&self, p: &ChanProtocol) -> String {
        match p {
            ChanProtocol::Any => "ANY".into(),
            ChanProtocol::Simple(item) => self.display_item(item),
            ChanProtocol::Named(id) => self
                .protocols
                .get(*id)
                .map_or("?".into(), |p| p.name.clone()),
        }
    }

    /// Renders one protocol item for messages.
    pub fn display_item(&self, item: &ProtocolItem) -> String {
        match item {
            ProtocolItem::Data(t) => self.display(t),
            ProtocolItem::Counted { count, elem } => {
                format!("{}::[]{}", count.name(), self.display(elem))
            }
        }
    }

    /// Reports whether a value of type `from` may be used where `to` is expected: equal types,
    /// an open array accepting any length, or an error type on either side.
    pub fn compatible(&self, to: &Type, from: &Type) -> bool {
        match (to, from) {
            (Type::Error, _) | (_, Type::Error) => true,
            (Type::Array(n, a), Type::Array(m, b)) => {
                (n.is_none() || m.is_none() || n == m) && self.compatible(a, b)
            }
            (Type::Chan(p, _), Type::Chan(q, _)) => p == q || **p == ChanProtocol::Any,
            (Type::Port(a), Type::Port(b)) => self.compatible(a, b),
            _ => to == from,
        }
    }
}
