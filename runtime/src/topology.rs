//! Network shapes for `occ run --topology`: which node each link of each node leads to.
//!
//! Every node has at most four links, numbered 0-3. The numbering per shape (documented for
//! node programs, which address links by number):
//! - `tree3:N` (a ternary tree, the CARM topology): link 0 leads to the parent (`(i - 1) / 3`;
//!   unconnected at the root, node 0), links 1-3 to the children `3i + 1`, `3i + 2`, `3i + 3`.
//! - `pipeline:N`: link 0 to node `i - 1`, link 1 to node `i + 1` (unconnected at the ends).
//! - `ring:N`: as a pipeline, with node `N - 1`'s link 1 joined to node 0's link 0.
//! - `grid:WxH`: node `i = y * W + x`; link 0 north (`y - 1`), 1 east (`x + 1`), 2 south
//!   (`y + 1`), 3 west (`x - 1`); no wrap-around.
//! - `hypercube:D` (`D` at most 4): link `k` leads to node `i XOR 2^k`, on its link `k`.

use std::fmt;
use std::str::FromStr;

/// Links a node has.
pub const LINKS: usize = 4;
/// The most nodes a network may have.
pub const MAX_NODES: usize = 4096;

/// A network shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// A ternary tree of N nodes.
    Tree3(usize),
    /// N nodes in a line.
    Pipeline(usize),
    /// N nodes in a cycle.
    Ring(usize),
    /// A W x H mesh.
    Grid(usize, usize),
    /// A D-dimensional hypercube of 2^D nodes.
    Hypercube(u32),
}

/// One end of a link: a node and its link number.
pub type End = (usize, usize);

impl Shape {
    /// The number of nodes.
    pub fn nodes(&self) -> usize {
        match *self {
            Shape::Tree3(n) | Shape::Pipeline(n) | Shape::Ring(n) => n,
            Shape::Grid(w, h) => w * h,
            Shape::Hypercube(d) => 1 << d,
        }
    }

    /// Where link `k` of node `i` leads, if it is connected.
    pub fn neighbour(&self, i: usize, k: usize) -> Option<End> {
        let n = self.nodes();
        if i >= n || k >= LINKS {
            return None;
        }
        match *self {
            Shape::Tree3(_) => match k {
                0 => (i > 0).then(|| ((i - 1) / 3, i - 3 * ((i - 1) / 3))),
                _ => Some((3 * i + k, 0)).filter(|&(c, _)| c < n),
            },
            Shape::Pipeline(_) => match k {
                0 => (i > 0).then(|| (i - 1, 1)),
                1 => (i + 1 < n).then_some((i + 1, 0)),
                _ => None,
            },
            Shape::Ring(_) => match k {
                0 => Some(((i + n - 1) % n, 1)),
                1 => Some(((i + 1) % n, 0)),
                _ => None,
            },
            Shape::Grid(w, h) => {
                let (x, y) = (i % w, i / w);
                match k {
                    0 => (y > 0).then(|| (i - w, 2)),
                    1 => (x + 1 < w).then(|| (i + 1, 3)),
                    2 => (y + 1 < h).then(|| (i + w, 0)),
                    _ => (x > 0).then(|| (i - 1, 1)),
                }
            }
            Shape::Hypercube(d) => (k < d as usize).then(|| (i ^ (1 << k), k)),
        }
    }

    /// Every link direction, as (from, to): the output channel of link `from.1` of node
    /// `from.0` joined to the input channel of link `to.1` of node `to.0`. In node order.
    pub fn directions(&self) -> Vec<(End, End)> {
        (0..self.nodes())
            .flat_map(|i| (0..LINKS).map(move |k| (i, k)))
            .filter_map(|from| self.neighbour(from.0, from.1).map(|to| (from, to)))
            .collect()
    }
}

/// Why a shape was refused.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShapeError(pub String);

impl fmt::Display for ShapeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ShapeError {}

impl FromStr for Shape {
    type Err = ShapeError;

    /// Parses `tree3:13`, `pipeline:8`, `ring:13`, `grid:4x3` or `hypercube:3`.
    fn from_str(s: &str) -> Result<Shape, ShapeError> {
        let bad = |why: &str| ShapeError(format!("topology `{s}`: {why}"));
        let (kind, size) = s
            .split_once(':')
            .ok_or_else(|| bad("expected SHAPE:SIZE, e.g. tree3:13, ring:8, grid:4x3"))?;
        let count = |t: &str| {
            t.trim()
                .parse::<usize>()
                .map_err(|_| bad(&format!("`{t}` is not a node count")))
        };
        let shape = match kind.trim() {
            "tree3" | "tree" => Shape::Tree3(count(size)?),
            "pipeline" => Shape::Pipeline(count(size)?),
            "ring" => Shape::Ring(count(size)?),
            "grid" => {
                let (w, h) = size
                    .split_once('x')
                    .ok_or_else(|| bad("a grid is WIDTHxHEIGHT, e.g. grid:4x3"))?;
                Shape::Grid(count(w)?, count(h)?)
            }
            "hypercube" => {
                let d = count(size)?;
                if d > LINKS {
                    return Err(bad(&format!(
                        "a hypercube of dimension {d} needs {d} links per node, but a transputer has {LINKS}"
                    )));
                }
                Shape::Hypercube(d as u32)
            }
            other => {
                return Err(bad(&format!(
                    "unknown shape `{other}` (tree3, pipeline, ring, grid, hypercube)"
                )));
            }
        };
        match shape.nodes() {
            0 => Err(bad("a network needs at least one node")),
            n if n > MAX_NODES => Err(bad(&format!(
                "{n} nodes is more than the {MAX_NODES} a network may have"
            ))),
            _ => Ok(shape),
        }
    }
}

impl fmt::Display for Shape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Shape::Tree3(n) => write!(f, "tree3:{n}"),
            Shape::Pipeline(n) => write!(f, "pipeline:{n}"),
            Shape::Ring(n) => write!(f, "ring:{n}"),
            Shape::Grid(w, h) => write!(f, "grid:{w}x{h}"),
            Shape::Hypercube(d) => write!(f, "hypercube:{d}"),
        }
    }
}

#[cfg(test)]
mod test {
    use super::*;

    /// Every link direction has a matching one back, and no node uses a link twice.
    fn check_symmetric(s: Shape) {
        let dirs = s.directions();
        for &(a, b) in &dirs {
            assert!(
                dirs.contains(&(b, a)),
                "{s}: {a:?} -> {b:?} has no way back"
            );
            assert_eq!(s.neighbour(b.0, b.1), Some(a), "{s}");
        }
    }

    #[test]
    fn shapes_are_symmetric() {
        for s in [
            "tree3:13",
            "tree3:40",
            "tree3:1",
            "pipeline:8",
            "ring:13",
            "ring:2",
            "grid:4x3",
            "hypercube:3",
            "hypercube:4",
        ] {
            check_symmetric(s.parse().unwrap());
        }
    }

    #[test]
    fn tree_links() {
        let t = Shape::Tree3(13);
        assert_eq!(t.neighbour(0, 0), None);
        assert_eq!(t.neighbour(0, 1), Some((1, 0)));
        assert_eq!(t.neighbour(4, 0), Some((1, 1)));
        assert_eq!(t.neighbour(12, 0), Some((3, 3)));
        assert_eq!(t.neighbour(4, 1), None, "node 13 does not exist");
        assert_eq!(t.directions().len(), 2 * 12);
    }

    #[test]
    fn bad_shapes_are_refused_with_a_reason() {
        for (s, why) in [
            ("tree3:0", "at least one node"),
            ("hypercube:5", "a transputer has 4"),
            ("star:5", "unknown shape"),
            ("ring", "SHAPE:SIZE"),
            ("grid:4", "WIDTHxHEIGHT"),
            ("ring:100000", "more than"),
        ] {
            let e = s.parse::<Shape>().unwrap_err();
            assert!(e.0.contains(why), "{s}: {e}");
        }
    }
}
