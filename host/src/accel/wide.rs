//! A four-wide BVH traversed with 4-lane SIMD (glam's `Vec4`: SSE on x86-64, NEON on
//! AArch64, `simd128` on wasm32, where the browser's module traces with it), with
//! triangles tested four at a time.
//!
//! # Why our own
//! obvhs's CWBVH spent about 1 240 instructions per closest-hit query and 1 300 per
//! occlusion query on the 36-triangle Cornell box (callgrind; docs/performance.md): its
//! compressed 8-wide nodes are a GPU layout whose decoding dominates on small scenes,
//! and each triangle went through a callback one at a time. Here a node holds its four
//! children's boxes as six 4-lane rows (one slab test for all four), and a leaf holds up
//! to four triangles as nine 4-lane rows (one watertight test for all four).
//!
//! # Build
//! obvhs builds the binary hierarchy (PLOC with reinsertion, `medium_build`, one
//! triangle per leaf; `build::build_bvh2_without_clock`, the same on every target); it
//! is then collapsed top-down: a subtree of at most [`PACKET`] triangles becomes one
//! leaf packet, small sibling subtrees merge into one packet where the surface-area
//! heuristic favours it, and a node adopts the children of its largest (by surface
//! area) inner child until it has four children or none of them can be opened further. Empty child slots hold the point at +∞ as their box,
//! which no ray enters.
//!
//! # Exactness
//! The lane arithmetic is the scalar watertight test's (`triangle.rs`), operation for
//! operation, with no fused multiply-adds, so a lane's answer is bit-identical to the
//! scalar test on that triangle. A packet where any lane has an edge function of
//! exactly zero goes through the scalar test, which redoes those in f64. The slab test
//! runs on the padded leaf boxes (see `hit::box_padding`) and also widens each box's
//! far distance by 1 + 2γ₃ as pbrt-v4 does, so a ray through the rim of a flat box is
//! not lost to rounding. Boxes are tested from t = 0: no absolute near cut (obvhs's
//! CWBVH has one at 10⁻⁴, see `accel.rs`).
//!
//! # Traversal
//! Closest hit: the children a ray enters are visited nearest first; the others wait on
//! a stack with their entry distance and are dropped when popped beyond the closest hit
//! so far. Occlusion stops at the first hit and does not sort. The stack is a
//! `heapless::Vec` (nothing to clear per query) of 16 or 64 entries, chosen by the
//! hierarchy's depth (three entries per level at most); a deeper hierarchy, which only a
//! pathological build makes, gets a heap stack.
//!
//! Measured (callgrind, PT on the built-in box): about 45 instructions per node test and
//! 131 per packet test; a closest-hit query visits 2.6 nodes and 2.1 packets there.

use glam::{Vec3A, Vec4};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::ray::Ray as BvhRay;

use super::hit::SLAB_WIDEN;
use super::isa::{self, Isa, IsaError, Kernels};
use super::triangle::WatertightRay;

/// Triangles per leaf packet (the SIMD width).
pub const PACKET: usize = isa::KERNEL_LANES;

/// Child reference: an inner node's index, or `LEAF | packet index`, or [`EMPTY`]
/// (never followed: an empty slot's box is never entered).
const LEAF: u32 = 1 << 31;
const EMPTY: u32 = u32::MAX;

/// Four children's boxes: rows min x, min y, min z, max x, max y, max z, one lane each.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct Node {
    bounds: [[f32; 4]; 6],
    child: [u32; 4],
}

/// Up to four triangles: `v[vertex][axis]` holds that coordinate of each lane's
/// triangle. Dead lanes hold NaN, which fails every test below (NaN compares
/// unequal to zero and is neither positive nor negative, so only the final `t > 0`
/// check drops it).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct Packet {
    v: [[[f32; 4]; 3]; 3],
    /// Leaf slot of lane 0; lane `l` is slot `first + l`.
    first: u32,
    /// Live lanes (1 to 4), the low ones.
    count: u32,
}

impl Packet {
    /// The triangle in lane `l`.
    fn triangle(&self, l: usize) -> [Vec3A; 3] {
        core::array::from_fn(|k| Vec3A::new(self.v[k][0][l], self.v[k][1][l], self.v[k][2][l]))
    }
}

/// The four-wide hierarchy with its triangles packed in leaf order.
#[derive(Clone, Debug)]
pub struct Wide {
    nodes: Vec<Node>,
    packets: Vec<Packet>,
    /// Leaf slot → index into the build input.
    order: Vec<u32>,
    /// The most entries a traversal can hold on its stack: three per level below the
    /// root (a node pushes all its entered children but the one it visits next).
    stack_need: usize,
    /// The instruction set the queries run with (module `isa`): one this machine offers.
    isa: Isa,
}

/// The per-ray values of the slab test.
struct SlabRay {
    origin: [Vec4; 3],
    inv: [Vec4; 3],
}

impl SlabRay {
    #[inline(always)]
    fn new(ray: &BvhRay) -> Self {
        let (o, inv) = (ray.origin, ray.inv_direction);
        Self { origin: [Vec4::splat(o.x), Vec4::splat(o.y), Vec4::splat(o.z)], inv: [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)] }
    }

    /// Entry distances and which of the four boxes the ray enters within [0, t_max].
    /// Each axis's two plane distances are ordered by min and max, whichever the sign of
    /// the direction. An empty slot's box is the point at +∞ (every distance ±∞, the
    /// far one never above the near one) and `t_max` is capped at `f32::MAX`, so an
    /// empty slot is never entered.
    #[inline(always)]
    fn test(&self, node: &Node, t_max: f32) -> (Vec4, u32) {
        let b = &node.bounds;
        let slab = |a: usize| {
            let (t0, t1) = ((Vec4::from(b[a]) - self.origin[a]) * self.inv[a], (Vec4::from(b[a + 3]) - self.origin[a]) * self.inv[a]);
            (t0.min(t1), t0.max(t1))
        };
        let ((n0, f0), (n1, f1), (n2, f2)) = (slab(0), slab(1), slab(2));
        let near = n0.max(n1).max(n2).max(Vec4::ZERO);
        let far = (f0.min(f1).min(f2) * SLAB_WIDEN).min(Vec4::splat(t_max.min(f32::MAX)));
        (near, near.cmple(far).bitmask())
    }
}

/// The per-ray values of the watertight test, splatted.
struct PacketRay<'a> {
    scalar: &'a WatertightRay,
    /// Input axis feeding the permuted x, y and z.
    axis: [usize; 3],
    origin: [Vec4; 3],
    shear: [Vec4; 3],
}

impl<'a> PacketRay<'a> {
    #[inline(always)]
    fn new(wt: &'a WatertightRay) -> Self {
        let (axis, origin, shear) = wt.parts();
        Self { scalar: wt, axis, origin: origin.map(Vec4::splat), shear: shear.map(Vec4::splat) }
    }

    /// Per lane: distance (∞ where missed) and the three edge functions and 1/det, for
    /// the triangles of `p` hit in (0, t_max). The lanes hit, as a bitmask.
    #[inline(always)]
    fn test(&self, p: &Packet, t_max: f32) -> Option<LaneHits> {
        let [kx, ky, kz] = self.axis;
        let [sx, sy, sz] = self.shear;
        let vertex = |k: usize| {
            let v = &p.v[k];
            let (x, y, z) = (Vec4::from(v[kx]) - self.origin[0], Vec4::from(v[ky]) - self.origin[1], Vec4::from(v[kz]) - self.origin[2]);
            (x + sx * z, y + sy * z, z)
        };
        let (ax, ay, az) = vertex(0);
        let (bx, by, bz) = vertex(1);
        let (cx, cy, cz) = vertex(2);
        let e0 = bx * cy - by * cx;
        let e1 = cx * ay - cy * ax;
        let e2 = ax * by - ay * bx;
        let zero = Vec4::ZERO;
        if (e0.cmpeq(zero) | e1.cmpeq(zero) | e2.cmpeq(zero)).any() {
            return self.scalar_fallback(p, t_max);
        }
        let negative = e0.cmplt(zero) | e1.cmplt(zero) | e2.cmplt(zero);
        let positive = e0.cmpgt(zero) | e1.cmpgt(zero) | e2.cmpgt(zero);
        let det = e0 + e1 + e2;
        let mut ok = !(negative & positive) & det.cmpne(zero);
        // Most packets a ray reaches lie beside it: leave before the distances.
        if !ok.any() {
            return None;
        }
        let t_scaled = e0 * (az * sz) + e1 * (bz * sz) + e2 * (cz * sz);
        let bound = Vec4::splat(t_max) * det;
        let below = det.cmplt(zero) & (t_scaled.cmpge(zero) | t_scaled.cmplt(bound));
        let above = det.cmpgt(zero) & (t_scaled.cmple(zero) | t_scaled.cmpgt(bound));
        ok &= !(below | above);
        if !ok.any() {
            return None;
        }
        let inv_det = Vec4::ONE / det;
        let t = t_scaled * inv_det;
        // NaN fails both comparisons.
        ok &= t.cmpgt(zero) & t.cmplt(Vec4::splat(t_max));
        let mask = ok.bitmask();
        (mask != 0).then(|| LaneHits { t: Vec4::select(ok, t, Vec4::INFINITY), e: [e0, e1, e2], inv_det, mask })
    }

    /// The scalar test lane by lane (an edge function rounded to zero: redone in f64).
    #[cold]
    fn scalar_fallback(&self, p: &Packet, t_max: f32) -> Option<LaneHits> {
        let (mut t, mut e, mut inv_det, mut mask) = ([f32::INFINITY; 4], [[0.0f32; 4]; 3], [1.0f32; 4], 0u32);
        for l in 0..p.count as usize {
            let [a, b, c] = p.triangle(l);
            if let Some((tl, bary)) = self.scalar.hit(a, b, c, t_max) {
                t[l] = tl;
                // Barycentrics as edge functions over a unit determinant.
                (0..3).for_each(|k| e[k][l] = bary[k]);
                inv_det[l] = 1.0;
                mask |= 1 << l;
            }
        }
        (mask != 0).then(|| LaneHits { t: Vec4::from(t), e: e.map(Vec4::from), inv_det: Vec4::from(inv_det), mask })
    }
}

/// What [`PacketRay::test`] found in one packet.
struct LaneHits {
    t: Vec4,
    e: [Vec4; 3],
    inv_det: Vec4,
    mask: u32,
}

impl LaneHits {
    /// The nearest lane (the lowest on a tie) and its distance.
    #[inline(always)]
    fn nearest(&self) -> (usize, f32) {
        let t = self.t.min_element();
        let lane = (self.t.cmpeq(Vec4::splat(t)).bitmask() & self.mask).trailing_zeros() as usize;
        (lane, t)
    }
}

/// A traversal stack of at most `N` entries (item, entry distance), each packed in a
/// `u64` (distance bits high, item low). Sized from the hierarchy (`Wide::stack_need`),
/// so pushes always find room. A `heapless::Vec`, not a zeroed array: clearing 16
/// entries per query cost about 30 instructions, 1.8 % of a PT sample's (callgrind).
struct Stack<const N: usize> {
    items: heapless::Vec<u64, N>,
}

impl<const N: usize> Stack<N> {
    #[inline(always)]
    fn new() -> Self {
        Self { items: heapless::Vec::new() }
    }

    #[inline(always)]
    fn push(&mut self, item: u32, t: f32) {
        // Never full (sized from the depth); if a wrong size ever let it fill, dropping
        // the entry would lose hits silently: stop instead, as an array index would.
        let full = self.items.push((t.to_bits() as u64) << 32 | item as u64).is_err();
        assert!(!full, "traversal stack sized from the hierarchy's depth overflowed");
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, f32)> {
        self.items.pop().map(|v| (v as u32, f32::from_bits((v >> 32) as u32)))
    }
}

/// A stack for hierarchies deeper than any fixed size here (a pathological build).
struct HeapStack(Vec<(u32, f32)>);

/// What the traversals need of a stack.
trait TraversalStack {
    fn push(&mut self, item: u32, t: f32);
    fn pop(&mut self) -> Option<(u32, f32)>;
}

impl<const N: usize> TraversalStack for Stack<N> {
    #[inline(always)]
    fn push(&mut self, item: u32, t: f32) {
        Stack::push(self, item, t)
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, f32)> {
        Stack::pop(self)
    }
}

impl TraversalStack for HeapStack {
    fn push(&mut self, item: u32, t: f32) {
        self.0.push((item, t))
    }
    fn pop(&mut self) -> Option<(u32, f32)> {
        self.0.pop()
    }
}

impl Wide {
    /// Build over triangles `tris` with (padded) boxes `boxes`, both non-empty and of
    /// equal length.
    pub fn build(tris: &[[Vec3A; 3]], boxes: &[Aabb]) -> Self {
        let params = BvhBuildParams { max_prims_per_leaf: 1, ..BvhBuildParams::medium_build() };
        let bvh2 = super::build::build_bvh2_without_clock(boxes, params);
        Collapse::new(&bvh2, tris).run()
    }

    /// Leaf slot → index into the build input.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Heap bytes of the nodes, the leaf packets and the leaf order.
    pub fn heap_bytes(&self) -> u64 {
        (self.nodes.capacity() * size_of::<Node>() + self.packets.capacity() * size_of::<Packet>() + self.order.capacity() * size_of::<u32>()) as u64
    }

    /// The instruction set the queries run with.
    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// Run the queries with `isa`; refused (and nothing changed) if this machine does
    /// not offer it. Every set gives the same answers bit for bit (module `isa`).
    pub fn set_isa(&mut self, isa: Isa) -> Result<(), IsaError> {
        self.isa = Isa::from_name(isa.name())?;
        Ok(())
    }

    /// Closest hit in (0, ray.tmax): leaf slot, distance and barycentrics.
    #[inline]
    pub fn closest(&self, ray: &BvhRay, wt: &WatertightRay) -> Option<(usize, f32, [f32; 3])> {
        isa::closest(self, ray, wt)
    }

    /// True if anything lies in (0, ray.tmax); stops at the first hit.
    #[inline]
    pub fn occluded(&self, ray: &BvhRay, wt: &WatertightRay) -> bool {
        isa::occluded(self, ray, wt)
    }

    #[inline(always)]
    fn closest_with(&self, ray: &BvhRay, wt: &WatertightRay, mut stack: impl TraversalStack) -> Option<(usize, f32, [f32; 3])> {
        let (slab, tri) = (SlabRay::new(ray), PacketRay::new(wt));
        let mut t_max = ray.tmax;
        // The closest hit so far: leaf slot (u32::MAX for none), lane, and its packet's
        // barycentrics (all lanes; the winner's is read out at the end).
        let (mut best_slot, mut best_lane, mut best_bary) = (u32::MAX, 0usize, [Vec4::ZERO; 3]);
        let mut item = 0u32;
        loop {
            if item & LEAF == 0 {
                let node = &self.nodes[item as usize];
                let (near, mut mask) = slab.test(node, t_max);
                if mask != 0 {
                    // Visit the nearest child next; the others wait, farthest deepest.
                    let near = near.to_array();
                    let mut order = [(0u32, 0.0f32); 4];
                    let mut n = 0;
                    while mask != 0 {
                        let c = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let entry = (node.child[c], near[c]);
                        // Insertion by descending entry distance.
                        let mut k = n;
                        while k > 0 && order[k - 1].1 < entry.1 {
                            order[k] = order[k - 1];
                            k -= 1;
                        }
                        order[k] = entry;
                        n += 1;
                    }
                    order[..n - 1].iter().for_each(|&(c, t)| stack.push(c, t));
                    item = order[n - 1].0;
                    continue;
                }
            } else {
                let p = &self.packets[(item & !LEAF) as usize];
                if let Some(hits) = tri.test(p, t_max) {
                    let (lane, t) = hits.nearest();
                    t_max = t;
                    let [e0, e1, e2] = hits.e;
                    (best_slot, best_lane, best_bary) = (p.first + lane as u32, lane, [e0 * hits.inv_det, e1 * hits.inv_det, e2 * hits.inv_det]);
                }
            }
            loop {
                let Some((next, entry)) = stack.pop() else {
                    // Lane by lane, not `array::map` (which was left out of line).
                    let [b0, b1, b2] = best_bary;
                    let lane = |b: Vec4| b.to_array()[best_lane];
                    return (best_slot != u32::MAX).then(|| (best_slot as usize, t_max, [lane(b0), lane(b1), lane(b2)]));
                };
                if entry <= t_max {
                    item = next;
                    break;
                }
            }
        }
    }

    #[inline(always)]
    fn occluded_with(&self, ray: &BvhRay, wt: &WatertightRay, mut stack: impl TraversalStack) -> bool {
        let (slab, tri) = (SlabRay::new(ray), PacketRay::new(wt));
        let mut item = 0u32;
        loop {
            if item & LEAF == 0 {
                let node = &self.nodes[item as usize];
                let (_, mut mask) = slab.test(node, ray.tmax);
                while mask != 0 {
                    let c = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    stack.push(node.child[c], 0.0);
                }
            } else if tri.test(&self.packets[(item & !LEAF) as usize], ray.tmax).is_some() {
                return true;
            }
            match stack.pop() {
                Some((next, _)) => item = next,
                None => return false,
            }
        }
    }
}

/// The traversal module `isa` compiles for each instruction set.
impl Kernels for Wide {
    fn isa(&self) -> Isa {
        self.isa
    }

    #[inline(always)]
    fn closest_inline(&self, ray: &BvhRay, wt: &WatertightRay) -> Option<(usize, f32, [f32; 3])> {
        match self.stack_need {
            0..=16 => self.closest_with(ray, wt, Stack::<16>::new()),
            17..=64 => self.closest_with(ray, wt, Stack::<64>::new()),
            _ => self.closest_with(ray, wt, HeapStack(Vec::with_capacity(self.stack_need))),
        }
    }

    #[inline(always)]
    fn occluded_inline(&self, ray: &BvhRay, wt: &WatertightRay) -> bool {
        match self.stack_need {
            0..=16 => self.occluded_with(ray, wt, Stack::<16>::new()),
            17..=64 => self.occluded_with(ray, wt, Stack::<64>::new()),
            _ => self.occluded_with(ray, wt, HeapStack(Vec::with_capacity(self.stack_need))),
        }
    }
}

/// The top-down collapse of a binary hierarchy into [`Wide`].
struct Collapse<'a> {
    bvh2: &'a Bvh2,
    tris: &'a [[Vec3A; 3]],
    /// Triangles under each binary node.
    counts: Vec<u32>,
    out: Wide,
}

impl<'a> Collapse<'a> {
    fn new(bvh2: &'a Bvh2, tris: &'a [[Vec3A; 3]]) -> Self {
        let nodes = &bvh2.nodes;
        // Children before parents: reverse of a pre-order walk.
        let mut preorder = Vec::with_capacity(nodes.len());
        let mut todo = vec![0u32];
        while let Some(n) = todo.pop() {
            preorder.push(n);
            let node = &nodes[n as usize];
            if !node.is_leaf() {
                todo.extend([node.first_index, node.first_index + 1]);
            }
        }
        let mut counts = vec![0u32; nodes.len()];
        for &n in preorder.iter().rev() {
            let node = &nodes[n as usize];
            counts[n as usize] = if node.is_leaf() { node.prim_count } else { counts[node.first_index as usize] + counts[node.first_index as usize + 1] };
        }
        let capacity = tris.len();
        Self {
            bvh2,
            tris,
            counts,
            out: Wide {
                nodes: Vec::new(),
                packets: Vec::with_capacity(capacity / 2 + 1),
                order: Vec::with_capacity(capacity),
                stack_need: 0,
                isa: Isa::best(),
            },
        }
    }

    fn run(mut self) -> Wide {
        // The root always becomes a wide node.
        let root_children = if self.counts[0] as usize <= PACKET { vec![self.group(0)] } else { self.open(0) };
        // (children, wide node, its depth below the root)
        let mut todo = vec![(root_children, 0usize, 0usize)];
        self.out.nodes.push(Self::empty_node());
        while let Some((children, slot, depth)) = todo.pop() {
            self.out.stack_need = self.out.stack_need.max(3 * (depth + 1));
            for (lane, g) in children.iter().enumerate() {
                let node = &mut self.out.nodes[slot];
                for a in 0..3 {
                    node.bounds[a][lane] = g.aabb.min[a];
                    node.bounds[a + 3][lane] = g.aabb.max[a];
                }
                if g.count as usize <= PACKET {
                    let packet = self.packet(&g.nodes);
                    self.out.nodes[slot].child[lane] = LEAF | packet;
                } else {
                    let index = self.out.nodes.len();
                    self.out.nodes.push(Self::empty_node());
                    self.out.nodes[slot].child[lane] = index as u32;
                    let grandchildren = self.open(g.nodes[0]);
                    todo.push((grandchildren, index, depth + 1));
                }
            }
        }
        self.out
    }

    /// Every slot empty: its box the point at +∞ (see `SlabRay::test`).
    fn empty_node() -> Node {
        Node { bounds: [[f32::INFINITY; 4]; 6], child: [EMPTY; 4] }
    }

    fn group(&self, n: u32) -> Group {
        Group { nodes: vec![n], count: self.counts[n as usize], aabb: self.bvh2.nodes[n as usize].aabb }
    }

    /// Up to four groups of descendants of inner binary node `n` that together hold its
    /// triangles. Start from its two children and repeat, while anything changes:
    /// - merge the two small groups (together at most a packet) whose merged box has the
    ///   least surface area, if it is below the sum of theirs (one packet test then
    ///   costs less, by the surface-area heuristic, than the two it replaces: the two
    ///   triangles of a quad always merge);
    /// - open the largest group holding more than a packet into its two children, while
    ///   there is room.
    fn open(&self, n: u32) -> Vec<Group> {
        let nodes = &self.bvh2.nodes;
        let first = nodes[n as usize].first_index;
        let mut children = vec![self.group(first), self.group(first + 1)];
        loop {
            let mut merge: Option<(usize, usize, Aabb)> = None;
            for i in 0..children.len() {
                for j in i + 1..children.len() {
                    let (a, b) = (&children[i], &children[j]);
                    if (a.count + b.count) as usize > PACKET {
                        continue;
                    }
                    let union = a.aabb.union(&b.aabb);
                    let gain = a.aabb.half_area() + b.aabb.half_area() - union.half_area();
                    if gain >= 0.0 && merge.is_none_or(|(_, _, m)| union.half_area() < m.half_area()) {
                        merge = Some((i, j, union));
                    }
                }
            }
            if let Some((i, j, union)) = merge {
                let b = children.swap_remove(j);
                let a = &mut children[i];
                a.nodes.extend(b.nodes);
                a.count += b.count;
                a.aabb = union;
                continue;
            }
            if children.len() == 4 {
                break;
            }
            let widest =
                children.iter().enumerate().filter(|(_, g)| g.count as usize > PACKET).max_by(|a, b| a.1.aabb.half_area().total_cmp(&b.1.aabb.half_area()));
            let Some((i, _)) = widest else { break };
            let f = nodes[children[i].nodes[0] as usize].first_index;
            children[i] = self.group(f);
            children.push(self.group(f + 1));
        }
        children
    }

    /// Pack the (at most four) triangles under binary nodes `roots`; returns the packet
    /// index.
    fn packet(&mut self, roots: &[u32]) -> u32 {
        let nodes = &self.bvh2.nodes;
        let first = self.out.order.len() as u32;
        let mut todo: Vec<u32> = roots.iter().rev().copied().collect();
        while let Some(m) = todo.pop() {
            let node = &nodes[m as usize];
            if node.is_leaf() {
                let range = node.first_index as usize..(node.first_index + node.prim_count) as usize;
                self.out.order.extend_from_slice(&self.bvh2.primitive_indices[range]);
            } else {
                todo.extend([node.first_index + 1, node.first_index]);
            }
        }
        let count = self.out.order.len() as u32 - first;
        let mut v = [[[f32::NAN; 4]; 3]; 3];
        for (lane, &input) in self.out.order[first as usize..].iter().enumerate() {
            let t = &self.tris[input as usize];
            for (k, p) in t.iter().enumerate() {
                for a in 0..3 {
                    v[k][a][lane] = p[a];
                }
            }
        }
        self.out.packets.push(Packet { v, first, count });
        self.out.packets.len() as u32 - 1
    }
}

/// Binary subtrees that become one child of a wide node: a single subtree, or several
/// small ones merged into one leaf packet.
struct Group {
    nodes: Vec<u32>,
    count: u32,
    aabb: Aabb,
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3a;

    fn build(tris: &[[Vec3A; 3]]) -> Wide {
        let boxes: Vec<Aabb> = tris.iter().map(|v| Aabb::from_points(v)).collect();
        Wide::build(tris, &boxes)
    }

    /// Every ray along +z through a triangle's centroid, against the scalar test over all
    /// triangles: the same slot, distance and barycentrics bit for bit, and occlusion
    /// agrees.
    fn check_against_scalar(tris: &[[Vec3A; 3]], wide: &Wide) {
        for (i, t) in tris.iter().enumerate() {
            let c = (t[0] + t[1] + t[2]) / 3.0;
            let (o, d) = (c - vec3a(0.0, 0.0, 5.0), vec3a(1e-30, 1e-30, 1.0));
            let ray = BvhRay { origin: o, direction: d, inv_direction: Vec3A::ONE / d, tmin: 0.0, tmax: f32::INFINITY };
            let wt = WatertightRay::new(o, d);
            let want =
                tris.iter().enumerate().filter_map(|(k, v)| wt.hit(v[0], v[1], v[2], f32::INFINITY).map(|(t, b)| (k, t, b))).min_by(|a, b| a.1.total_cmp(&b.1));
            let got = wide.closest(&ray, &wt).map(|(slot, t, b)| (wide.order()[slot] as usize, t, b));
            assert_eq!(got, want, "ray through triangle {i}");
            assert!(wide.occluded(&ray, &wt), "ray through triangle {i}");
        }
    }

    /// Triangles at exponentially growing distances make a deep tree (PLOC chains them):
    /// deeper than the 16-entry stack covers, so the 64-entry one runs; then the same
    /// tree through the heap stack (forced: no build here is that deep). Seen failing
    /// with `stack_need` counted as one entry per level instead of three.
    #[test]
    fn deep_trees_use_the_larger_stacks() {
        let tris: Vec<[Vec3A; 3]> = (0..160)
            .map(|k| {
                let x = 1.2f32.powi(k);
                [vec3a(x, 0.0, 0.0), vec3a(x + 0.1 * x.max(1.0), 0.0, 0.0), vec3a(x, 0.1 * x.max(1.0), 0.0)]
            })
            .collect();
        let mut wide = build(&tris);
        assert!((17..=64).contains(&wide.stack_need), "stack need {}", wide.stack_need);
        check_against_scalar(&tris, &wide);
        wide.stack_need = 65;
        check_against_scalar(&tris, &wide);
    }

    /// One to five triangles: a root holding one leaf, and one packet plus a second.
    #[test]
    fn tiny_inputs() {
        for n in 1..=5 {
            let tris: Vec<[Vec3A; 3]> = (0..n).map(|k| [vec3a(k as f32, 0.0, 0.0), vec3a(k as f32 + 0.5, 0.0, 0.0), vec3a(k as f32, 0.5, 0.0)]).collect();
            let wide = build(&tris);
            assert_eq!(wide.order().len(), n);
            check_against_scalar(&tris, &wide);
        }
    }
    /// Every instruction set this machine offers answers as the baseline does, bit for
    /// bit: closest slot, distance and barycentrics, and occlusion, for random rays and
    /// for rays aimed at the shared vertices and edges of a grid (where two triangles
    /// tie and the watertight test's f64 fallback runs), at several `t_max`. Seen
    /// failing with the AVX2 copy given `ray.tmax * 0.999` for occlusion (1 answer of 3000 differs).
    #[test]
    fn every_instruction_set_gives_the_same_hits() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 40) as f32) / (1u64 << 24) as f32
        };
        // A 12 × 12 grid of quads (two triangles each) in z = 0, and 200 random triangles.
        let mut tris = Vec::new();
        for (i, j) in (0..12).flat_map(|i| (0..12).map(move |j| (i as f32, j as f32))) {
            let (a, b, c, d) = (vec3a(i, j, 0.0), vec3a(i + 1.0, j, 0.0), vec3a(i + 1.0, j + 1.0, 0.0), vec3a(i, j + 1.0, 0.0));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
        for _ in 0..200 {
            let c = vec3a(12.0 * next(), 12.0 * next(), 4.0 * next() - 2.0);
            tris.push([c, c + vec3a(next() - 0.5, next() - 0.5, next() - 0.5), c + vec3a(next() - 0.5, next() - 0.5, next() - 0.5)]);
        }
        let mut rays = Vec::new();
        for k in 0..3000 {
            let o = vec3a(16.0 * next() - 2.0, 16.0 * next() - 2.0, 6.0 * next() - 3.0);
            let target = if k % 3 == 0 {
                // A grid vertex or an edge's midpoint.
                vec3a((next() * 13.0).floor(), (next() * 26.0).floor() * 0.5, 0.0)
            } else {
                vec3a(12.0 * next(), 12.0 * next(), 4.0 * next() - 2.0)
            };
            let tmax = [f32::INFINITY, 3.0, 10.0][k % 3];
            rays.push((o, (target - o).normalize(), tmax));
        }
        let mut wide = build(&tris);
        type Answer = (Option<(usize, f32, [f32; 3])>, bool);
        let answers = |wide: &Wide| -> Vec<Answer> {
            rays.iter()
                .map(|&(o, d, tmax)| {
                    let ray = BvhRay { origin: o, direction: d, inv_direction: Vec3A::ONE / d, tmin: 0.0, tmax };
                    let wt = WatertightRay::new(o, d);
                    (wide.closest(&ray, &wt), wide.occluded(&ray, &wt))
                })
                .collect()
        };
        let offered = Isa::offered();
        wide.set_isa(offered[0]).unwrap();
        let want = answers(&wide);
        assert!(want.iter().filter(|a| a.0.is_some()).count() > 1000, "too few hits to compare");
        for &isa in &offered[1..] {
            wide.set_isa(isa).unwrap();
            let got = answers(&wide);
            let differ = want
                .iter()
                .zip(&got)
                .filter(|(a, b)| {
                    a.0.map(|h| (h.0, h.1.to_bits(), h.2.map(f32::to_bits))) != b.0.map(|h| (h.0, h.1.to_bits(), h.2.map(f32::to_bits))) || a.1 != b.1
                })
                .count();
            assert_eq!(differ, 0, "{isa}: {differ} of {} answers differ from {}", rays.len(), offered[0]);
        }
    }
}
