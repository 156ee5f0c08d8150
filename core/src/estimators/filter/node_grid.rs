//! Where a pass finds kernel neighbours: its nodes in two grids by side, camera-kind
//! nodes (camera nodes and light nodes' twins) in one and light nodes in the other.
//!
//! The weights ask for one side at a time: the camera techniques of a segment sum over
//! camera nodes around its start, the light techniques over light nodes around its end
//! ([`super::bidir`]). In one grid each of those queries scanned and rejected the other
//! side's nodes, half of what it found with bidirectional filtering. A row reuses both
//! sides, so it queries both grids, the camera side first. Emission nodes, on the lights
//! and nobody's neighbour, are in neither (so that queries near a small light do not
//! visit every light path's origin).
//!
//! Both grids are [`CellGrid`]s for queries of radius √2 r (the disk kernel's support
//! reaches that far from its centre). [`FilterPass`](super::FilterPass) sorts its nodes
//! into [`NodeGrid::order`] (camera side, then light side, then the rest), so a query
//! reads nodes from a few contiguous runs.

use alloc::vec::Vec;

use super::nodes::{Node, NodeKind};
use crate::math::Vec3;
use crate::merge::CellGrid;

/// The two sides of a pass's nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Camera nodes and twins.
    Camera,
    /// Light nodes (bridges included).
    Light,
}

impl Side {
    /// The grid a node is in, if any.
    #[inline]
    pub fn of(node: &Node) -> Option<Side> {
        match node.kind {
            NodeKind::Camera => Some(Side::Camera),
            NodeKind::Light => Some(Side::Light),
            NodeKind::Emission => None,
        }
    }
}

/// The pass's nodes in a camera-side and a light-side grid.
#[derive(Clone, Debug, Default)]
pub struct NodeGrid {
    camera: CellGrid,
    light: CellGrid,
}

impl NodeGrid {
    /// Rebuild over `nodes` for queries of radius `radius`. Queries report node indices.
    pub fn build(&mut self, nodes: &[Node], radius: f32) {
        let on = |side| nodes.iter().map(move |n| if Side::of(n) == Some(side) { n.hit.p } else { Vec3::NAN });
        self.camera.build(on(Side::Camera), radius);
        self.light.build(on(Side::Light), radius);
    }

    /// The query radius.
    pub fn radius(&self) -> f32 {
        self.camera.radius()
    }

    /// Bytes held (capacity).
    pub fn size_bytes(&self) -> usize {
        self.camera.size_bytes() + self.light.size_bytes()
    }

    /// Call `visit(i)` for every node i of `side` within the query radius of `p`.
    #[inline]
    pub fn query_side(&self, side: Side, p: Vec3, visit: impl FnMut(u32)) {
        match side {
            Side::Camera => self.camera.query(p, visit),
            Side::Light => self.light.query(p, visit),
        }
    }

    /// Call `visit(i)` for every node i within the query radius of `p`: the camera side's,
    /// then the light side's.
    #[inline]
    pub fn query(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        self.camera.query(p, &mut visit);
        self.light.query(p, &mut visit);
    }

    /// The node indices in grid order: the camera side's slots, then the light side's.
    pub fn order(&self) -> impl Iterator<Item = u32> + '_ {
        self.camera.order().iter().chain(self.light.order()).copied()
    }

    /// Nodes in either grid.
    pub fn len(&self) -> usize {
        self.camera.len() + self.light.len()
    }

    /// Is neither grid holding a node?
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Each node's position in `order`, the others after them in their own order: the
/// permutation [`NodeGrid::order`] asks for, into `new_index` (cleared first).
pub fn grid_permutation(n: usize, order: impl Iterator<Item = u32>, new_index: &mut Vec<u32>) {
    new_index.clear();
    super::graph::reserve_headroom(new_index, n);
    new_index.resize(n, u32::MAX);
    let mut slot = 0u32;
    for old in order {
        new_index[old as usize] = slot;
        slot += 1;
    }
    for k in new_index.iter_mut().filter(|k| **k == u32::MAX) {
        *k = slot;
        slot += 1;
    }
}
