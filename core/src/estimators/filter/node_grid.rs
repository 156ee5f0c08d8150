//! Where a pass finds kernel neighbours: its nodes in two grids by side, camera-kind
//! nodes (camera nodes and light nodes' twins) in one and light nodes in the other, and
//! the disk kernel's test over them ([`KernelPoint`], [`NodeGrid::query_kernel`]).
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
use crate::segment::Kernel;

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

/// What a kernel test reads of a node, packed in 28 bytes (a node takes 236). Every
/// grid candidate is tested, and many are then skipped (Dirac nodes, nodes of the
/// other side, nodes outside the kernel) without reading their node.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct KernelPoint {
    /// The node's end.
    pub p: Vec3,
    /// Its side normal ([`Kernel::side_normal`]): the kernel's plane as a centre, and as
    /// a point in another's kernel its normal (whose sign the density ignores).
    pub side: Vec3,
    pub delta: bool,
    pub kind: NodeKind,
    /// Its kernel's radius over the pass's ([`Node::kernel_scale`]).
    pub scale: f32,
}

impl KernelPoint {
    pub fn of(node: &Node) -> Self {
        Self { p: node.hit.p, side: Kernel::side_normal(&node.hit, node.wo), delta: node.delta, kind: node.kind, scale: node.kernel_scale }
    }

    /// K(self → x): the density of `x` in this point's own kernel (the pass's `kernel`
    /// scaled by [`Self::scale`]).
    #[inline]
    pub fn kernel(&self, kernel: &Kernel, x: &KernelPoint) -> f64 {
        self.density_at(kernel, x.p, x.side)
    }

    /// K(self → x) for the point `x` with normal `nx` (either orientation): the same as
    /// [`super::Neighbourhood`]'s `kernel_at` of this point's node, without reading the node.
    #[inline]
    pub fn density_at(&self, kernel: &Kernel, x: Vec3, nx: Vec3) -> f64 {
        kernel.scaled(self.scale).density_around(self.p, self.side, x, nx).0 as f64
    }
}

/// Each node's kernel point, in node order.
pub fn kernel_points(nodes: &[Node]) -> Vec<KernelPoint> {
    nodes.iter().map(KernelPoint::of).collect()
}

/// The pass's nodes in a camera-side and a light-side grid.
#[derive(Clone, Debug, Default)]
pub struct NodeGrid {
    camera: CellGrid,
    light: CellGrid,
    /// What a kernel test reads of each grid's nodes, by slot.
    camera_kernels: KernelSlots,
    light_kernels: KernelSlots,
}

/// The disk kernels' data of a grid's nodes by slot, as structures of arrays: each node's
/// side normal ([`crate::segment::Kernel::side_normal`]), its kernel's scale and whether
/// it may take part (not Dirac). [`NodeGrid::query_kernel`] tests [`LANES`] of them at a
/// time.
#[derive(Clone, Debug, Default)]
struct KernelSlots {
    nx: Vec<f32>,
    ny: Vec<f32>,
    nz: Vec<f32>,
    scale: Vec<f32>,
    live: Vec<bool>,
}

impl KernelSlots {
    /// From the kernel points of the grid's nodes, in slot order.
    fn fill(&mut self, points: impl Iterator<Item = KernelPoint> + Clone) {
        for v in [&mut self.nx, &mut self.ny, &mut self.nz, &mut self.scale] {
            v.clear();
        }
        self.live.clear();
        self.nx.extend(points.clone().map(|k| k.side.x));
        self.ny.extend(points.clone().map(|k| k.side.y));
        self.nz.extend(points.clone().map(|k| k.side.z));
        self.scale.extend(points.clone().map(|k| k.scale));
        self.live.extend(points.map(|k| !k.delta));
    }

    fn size_bytes(&self) -> usize {
        (self.nx.capacity() + self.ny.capacity() + self.nz.capacity() + self.scale.capacity()) * 4 + self.live.capacity()
    }
}

/// Candidates a kernel query tests at a time.
const LANES: usize = 8;

/// Whose kernel [`NodeGrid::query_kernel`] evaluates (the pass's, scaled by the
/// owner's [`Node::kernel_scale`]).
#[derive(Clone, Copy, Debug)]
pub enum KernelOf {
    /// The centre's own, K(centre → node): the centre's point `p`, side normal `n` and
    /// kernel scale.
    Centre { p: Vec3, n: Vec3, scale: f32 },
    /// Each node's own, K(node → x) for the point `x` with normal `nx`.
    Nodes { x: Vec3, nx: Vec3 },
}

/// A node's end as the grids read it: 16 bytes, where a node takes 236 (a pass builds
/// its grids up to twice, each build reading every node twice).
#[derive(Clone, Copy, Debug)]
pub struct NodeEnd {
    pub p: Vec3,
    pub side: Option<Side>,
}

impl NodeEnd {
    pub fn of(node: &Node) -> Self {
        Self { p: node.hit.p, side: Side::of(node) }
    }
}

impl NodeGrid {
    /// Rebuild over `nodes` for queries of radius `radius`. Queries report node indices.
    pub fn build(&mut self, nodes: &[Node], radius: f32) {
        // (Straight from the nodes: no list of ends to allocate.)
        self.build_over(nodes.iter().map(NodeEnd::of), radius);
        let point = |&i: &u32| KernelPoint::of(&nodes[i as usize]);
        self.camera_kernels.fill(self.camera.order().iter().map(point));
        self.light_kernels.fill(self.light.order().iter().map(point));
    }

    /// Rebuild the grids over the nodes' `ends`, leaving the kernel data stale: only
    /// [`Self::query`] and [`Self::order`] may follow, until [`Self::relabel_sorted`].
    pub fn build_positions(&mut self, ends: &[NodeEnd], radius: f32) {
        self.build_over(ends.iter().copied(), radius);
    }

    fn build_over(&mut self, ends: impl ExactSizeIterator<Item = NodeEnd> + Clone, radius: f32) {
        let on = |side| ends.clone().map(move |e| if e.side == Some(side) { e.p } else { Vec3::NAN });
        self.camera.build(on(Side::Camera), radius);
        self.light.build(on(Side::Light), radius);
    }

    /// After the nodes were put in [`Self::order`] (`points` their kernel points, in that
    /// order): the grids a rebuild over them would give, without rebuilding. Node k now
    /// lies in the camera grid's slot k, node (camera nodes) + k in the light grid's
    /// slot k: a stable counting sort of nodes already in bucket order leaves them where
    /// they are (`sorting_nodes_keeps_every_query_and_link`).
    /// Returns the light side's nodes (they follow the camera side's).
    pub fn relabel_sorted(&mut self, points: &[KernelPoint]) -> core::ops::Range<usize> {
        let (nc, nl) = (self.camera.len(), self.light.len());
        self.camera.relabel_in_order(0, points.len());
        self.light.relabel_in_order(nc, points.len());
        self.camera_kernels.fill(points[..nc].iter().copied());
        self.light_kernels.fill(points[nc..nc + nl].iter().copied());
        nc..nc + nl
    }

    /// Call `visit(i, k)` for every non-Dirac node i of `side` (both, camera side first,
    /// for `None`) within the query radius of `p` whose disk kernel density `k` (as
    /// `of` says whose) is positive: the nodes [`Self::query`] reports, in its order,
    /// less those the kernel leaves out, with the density
    /// [`crate::segment::Kernel::density_around`] gives, to the bit.
    ///
    /// The candidates are tested `LANES` (8) at a time without a branch (the ball, the
    /// kernel's disk and slab, the node's liveness), and only those inside reach `visit`.
    /// One at a time, about four candidates were rejected per node kept, each rejection a
    /// branch no predictor could learn.
    #[inline]
    pub fn query_kernel(&self, side: Option<Side>, p: Vec3, kernel: Kernel, of: KernelOf, mut visit: impl FnMut(u32, f32)) {
        // The Dirac kernel has no continuous part: no node has a density in it.
        let Kernel::Disk { radius } = kernel else { return };
        if side != Some(Side::Light) {
            Self::query_kernel_in(&self.camera, &self.camera_kernels, p, radius, of, &mut visit);
        }
        if side != Some(Side::Camera) {
            Self::query_kernel_in(&self.light, &self.light_kernels, p, radius, of, &mut visit);
        }
    }

    #[inline]
    fn query_kernel_in(grid: &CellGrid, kernels: &KernelSlots, p: Vec3, radius: f32, of: KernelOf, visit: &mut impl FnMut(u32, f32)) {
        let (xs, ys, zs) = grid.positions();
        let order = grid.order();
        let r = grid.radius();
        let r2 = r * r;
        grid.query_ranges(p, |slots| {
            let mut j = slots.start;
            while j < slots.end {
                let full = j + LANES <= slots.end;
                // A full block reads the slots as they lie; the last, partial one a copy
                // padded with points that are never inside (NaN compares false).
                let pad = |v: &[f32]| -> [f32; LANES] { core::array::from_fn(|l| if j + l < slots.end { v[j + l] } else { f32::NAN }) };
                let block = |v: &[f32]| -> [f32; LANES] { if full { v[j..j + LANES].try_into().expect("a full block") } else { pad(v) } };
                let (x, y, z) = (block(xs), block(ys), block(zs));
                let (nx, ny, nz, scale) = (block(&kernels.nx), block(&kernels.ny), block(&kernels.nz), block(&kernels.scale));
                let mut k = [0.0f32; LANES];
                let mut mask = lanes(&x, &y, &z, &nx, &ny, &nz, &scale, p, r2, radius, of, &mut k);
                mask &= live_mask(&kernels.live[j..slots.end.min(j + LANES)]);
                while mask != 0 {
                    let l = mask.trailing_zeros() as usize;
                    visit(order[j + l], k[l]);
                    mask &= mask - 1;
                }
                j += LANES;
            }
        });
    }

    /// The query radius.
    pub fn radius(&self) -> f32 {
        self.camera.radius()
    }

    /// Bytes held (capacity).
    pub fn size_bytes(&self) -> usize {
        self.camera.size_bytes() + self.light.size_bytes() + self.camera_kernels.size_bytes() + self.light_kernels.size_bytes()
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

/// One block's kernel densities into `k` and the mask of its lanes inside both the
/// query ball (radius √`r2` around `p`, `Slots::scan`'s test in its order) and the kernel,
/// with a positive density.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn lanes(
    x: &[f32; LANES],
    y: &[f32; LANES],
    z: &[f32; LANES],
    nx: &[f32; LANES],
    ny: &[f32; LANES],
    nz: &[f32; LANES],
    scale: &[f32; LANES],
    p: Vec3,
    r2: f32,
    radius: f32,
    of: KernelOf,
    k: &mut [f32; LANES],
) -> u32 {
    let mut mask = 0u32;
    match of {
        KernelOf::Centre { p: c, n: cn, scale: centre_scale } => {
            let radius = radius * centre_scale;
            for l in 0..LANES {
                let q = Vec3::new(x[l], y[l], z[l]);
                let (dx, dy, dz) = (q.x - p.x, q.y - p.y, q.z - p.z);
                let ball = dx * dx + dy * dy + dz * dz <= r2;
                let (density, inside) = Kernel::disk_density(c, cn, radius, q, Vec3::new(nx[l], ny[l], nz[l]));
                k[l] = density;
                mask |= ((ball & inside & (density > 0.0)) as u32) << l;
            }
        }
        KernelOf::Nodes { x: at, nx: an } => {
            for l in 0..LANES {
                let q = Vec3::new(x[l], y[l], z[l]);
                let (dx, dy, dz) = (q.x - p.x, q.y - p.y, q.z - p.z);
                let ball = dx * dx + dy * dy + dz * dz <= r2;
                let (density, inside) = Kernel::disk_density(q, Vec3::new(nx[l], ny[l], nz[l]), radius * scale[l], at, an);
                k[l] = density;
                mask |= ((ball & inside & (density > 0.0)) as u32) << l;
            }
        }
    }
    mask
}

/// Bit l set where `live[l]` (fewer than [`LANES`] at a run's end).
#[inline(always)]
fn live_mask(live: &[bool]) -> u32 {
    live.iter().enumerate().fold(0, |m, (l, &b)| m | (b as u32) << l)
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
