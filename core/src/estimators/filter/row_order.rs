//! The order in which a filtering pass computes and holds its rows
//! ([`super::FilterPass::order_rows`]): the identity but on one range of nodes, sorted by
//! a key, so that rows whose kernels lie near each other are computed one after another.

use alloc::vec::Vec;

use super::graph::reserve_headroom;

/// The order of a pass's rows: the identity but on one range of nodes, which
/// [`super::FilterPass::order_rows`] sorts. Row `start + k` is node `order[k]`'s; node
/// `start + j`'s row is `start + position[j]`.
#[derive(Clone, Debug, Default)]
pub(super) struct RowOrder {
    start: usize,
    order: Vec<u32>,
    position: Vec<u32>,
    /// Scratch: the counting sort's buckets.
    counts: Vec<u32>,
}

impl RowOrder {
    /// Back to node order.
    pub(super) fn clear(&mut self) {
        self.order.clear();
        self.position.clear();
    }

    /// The node whose row is row `k`.
    #[inline]
    pub(super) fn node(&self, k: usize) -> usize {
        match k.checked_sub(self.start).and_then(|j| self.order.get(j)) {
            Some(&v) => v as usize,
            None => k,
        }
    }

    /// The row of node `v`.
    #[inline]
    pub(super) fn row(&self, v: u32) -> u32 {
        match (v as usize).checked_sub(self.start).and_then(|j| self.position.get(j)) {
            Some(&k) => (self.start as u32).wrapping_add(k),
            None => v,
        }
    }

    /// Sort `nodes` (out of `n`) by `key`, stably (a counting sort: keys past `n` share
    /// the last bucket).
    pub(super) fn sort(&mut self, nodes: core::ops::Range<usize>, n: usize, key: impl Fn(usize) -> u32) {
        self.start = nodes.start;
        let bucket = |v: usize| (key(v) as usize).min(n);
        self.counts.clear();
        reserve_headroom(&mut self.counts, n + 2);
        self.counts.resize(n + 2, 0);
        for v in nodes.clone() {
            self.counts[bucket(v) + 1] += 1;
        }
        for b in 1..self.counts.len() {
            self.counts[b] += self.counts[b - 1];
        }
        self.order.clear();
        reserve_headroom(&mut self.order, nodes.len());
        self.order.resize(nodes.len(), 0);
        for v in nodes.clone() {
            let b = bucket(v);
            self.order[self.counts[b] as usize] = v as u32;
            self.counts[b] += 1;
        }
        self.position.clear();
        reserve_headroom(&mut self.position, nodes.len());
        self.position.resize(nodes.len(), 0);
        for (k, &v) in self.order.iter().enumerate() {
            self.position[v as usize - self.start] = k as u32;
        }
    }

    pub(super) fn size_bytes(&self) -> usize {
        (self.order.capacity() + self.position.capacity() + self.counts.capacity()) * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimators::filter::graph::{FilterGraph, Rgb3};
    use crate::estimators::filter::nodes::NONE;

    /// Rows in a sorted order ([`crate::estimators::filter::FilterPass::order_rows`]):
    /// the order is a stable sort of its range by key and the identity elsewhere, `node`
    /// and `row` are inverses, and a
    /// graph built and propagated in that order (targets as rows) gives every node the
    /// L it has in node order, to the bit. Seen failing with the sort made unstable
    /// (ties placed last first: the order check), with `row` one past the right row, and
    /// with the positions not inverted (`position[k] = order[k]`). The estimators'
    /// images (the image hashes of PhF and BPF) fail with `map_rows` keeping the
    /// targets as node indices.
    #[test]
    fn rows_in_a_sorted_order_give_every_node_the_same_light() {
        let n = 300usize;
        let hash = |v: usize, salt: u64| {
            // A splitmix64 step: keys with ties and no order of their own.
            let mut z = (v as u64).wrapping_add(salt.wrapping_mul(0x9e37_79b9_7f4a_7c15));
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) % n as u64) as u32
        };
        let mut order = RowOrder::default();
        for (range, keys_past_n) in [(0..n, false), (40..250, false), (10..11, false), (37..300, true), (5..5, false)] {
            let key = |v: usize| if keys_past_n && v.is_multiple_of(7) { NONE } else { hash(v, 1) };
            order.sort(range.clone(), n, key);
            for k in 0..n {
                let v = order.node(k);
                assert_eq!(order.row(v as u32) as usize, k, "{range:?}: row of node {v}");
                if !range.contains(&k) {
                    assert_eq!(v, k, "{range:?}: rows outside the range keep their node");
                }
            }
            for k in range.start..range.end.saturating_sub(1) {
                let (a, b) = (order.node(k), order.node(k + 1));
                let (ka, kb) = (key(a).min(n as u32), key(b).min(n as u32));
                assert!(ka < kb || (ka == kb && a < b), "{range:?}: rows {k} and {} out of order", k + 1);
            }
            // A random graph: node v's row reuses a few nodes with weights below 1/4.
            let row_of = |v: usize| -> (Rgb3<f64>, Vec<(u32, Rgb3<f64>)>) {
                let e = [hash(v, 2) as f64 / n as f64, 0.5, 0.25];
                let pairs = (0..(v % 4) as u64).map(|j| (hash(v, 3 + j), [0.2 * hash(v, 9 + j) as f64 / n as f64, 0.1, 0.05])).collect();
                (e, pairs)
            };
            let (mut by_node, mut by_row) = (FilterGraph::<f64>::new(), FilterGraph::<f64>::new());
            for v in 0..n {
                let (e, pairs) = row_of(v);
                by_node.push_row(e, [0.0; 3], pairs);
            }
            for k in 0..n {
                let (e, pairs) = row_of(order.node(k));
                by_row.push_row(e, [0.0; 3], pairs.into_iter().map(|(t, c)| (order.row(t), c)));
            }
            let (a, b) = (by_node.propagate(5), by_row.propagate(5));
            for v in 0..n {
                assert_eq!(a[v], b[order.row(v as u32) as usize], "{range:?}: node {v}");
            }
        }
    }
}
