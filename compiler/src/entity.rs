//! Typed indices in the style of Cranelift's `cranelift-entity`: a newtype index per kind of
//! entity and a [`PrimaryMap`] that hands them out. Using a `TypeDefId` where a `ProtocolId` is
//! expected is then a compile error rather than a silent mix-up.

use std::marker::PhantomData;

/// A typed index into a [`PrimaryMap`].
pub trait EntityRef: Copy + Eq {
    /// Builds the index from its position.
    fn new(index: usize) -> Self;
    /// Returns the position this index stands for.
    fn index(self) -> usize;
}

/// Declares a `u32` newtype that implements [`EntityRef`].
#[macro_export]
macro_rules! entity_ref {
    ($(#[$meta:meta])* $name:ident) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $name(u32);

        impl $crate::entity::EntityRef for $name {
            fn new(index: usize) -> Self {
                $name(u32::try_from(index).unwrap_or(u32::MAX))
            }
            fn index(self) -> usize {
                self.0 as usize
            }
        }
    };
}

/// A vector that owns its entities and hands out typed indices for them.
#[derive(Debug, Clone)]
pub struct PrimaryMap<K, V> {
    items: Vec<V>,
    key: PhantomData<K>,
}

impl<K: EntityRef, V> Default for PrimaryMap<K, V> {
    fn default() -> Self {
        Self::new()
    }
}

impl<K: EntityRef, V> PrimaryMap<K, V> {
    /// Creates an empty map.
    pub fn new() -> Self {
        PrimaryMap {
            items: Vec::new(),
            key: PhantomData,
        }
    }

    /// Stores `value` and returns its new index.
    pub fn push(&mut self, value: V) -> K {
        self.items.push(value);
        K::new(self.items.len() - 1)
    }

    /// Returns the entity at `key`, if `key` came from this map.
    pub fn get(&self, key: K) -> Option<&V> {
        self.items.get(key.index())
    }

    /// Returns the entity at `key` mutably, if `key` came from this map.
    pub fn get_mut(&mut self, key: K) -> Option<&mut V> {
        self.items.get_mut(key.index())
    }

    /// Returns the number of entities.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Reports whether the map holds no entity.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// Iterates over `(index, entity)` pairs in creation order.
    pub fn iter(&self) -> impl Iterator<Item = (K, &V)> {
        self.items.iter().enumerate().map(|(i, v)| (K::new(i), v))
    }
}

impl<K: EntityRef, V> std::ops::Index<K> for PrimaryMap<K, V> {
    type Output = V;
    /// Panics only when `key` came from another map, which is a compiler bug.
    fn index(&self, key: K) -> &V {
        &self.items[key.index()]
    }
}

impl<K: EntityRef, V> std::ops::IndexMut<K> for PrimaryMap<K, V> {
    /// Panics only when `key` came from another map, which is a compiler bug.
    fn index_mut(&mut self, key: K) -> &mut V {
        &mut self.items[key.index()]
    }
}
