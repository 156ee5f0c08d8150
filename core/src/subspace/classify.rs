//! The classification functions κ_E and κ_L [SPCBPT section 6.4, 7.2].
//!
//! * **Distance** (eq. 18): `d = |Δp|² + σ²(1 − n·n') + k_d·σ²(1 − ω·ω')`, with
//!   σ² = the largest per-axis variance of the dataset's vertex positions (section 7.2.2),
//!   so the angular terms are measured in the scene's own length scale.
//! * **Centroids** are drawn from the dataset's sub-paths with probability ∝ the full
//!   path's contribution (section 6.4). We draw *without replacement* (Efraimidis–Spirakis
//!   keys `ln(u)/w`, the `count` largest win): the first pick is exactly ∝ w, and no two
//!   centroids coincide — a duplicate would be an id that nearest-centroid never returns,
//!   i.e. a permanently empty subspace wasting a row/column of Γ.
//! * **Decision tree** fitted to the nearest-centroid labels, because evaluating eq. 17
//!   costs O(N_S) distances per vertex. The paper splits a node while its weighted accuracy
//!   is below 99%, on an attribute chosen at random among position, normal and incident
//!   direction, at the centre of that attribute's bounds; the public code splits 8-ways at
//!   the midpoint of the 3-D attribute. Our choice: a *binary* split at the midpoint of the
//!   largest-extent axis of an attribute's bounds (the paper's threshold rule), the
//!   attribute being the one of the three whose split gives the purest children by the
//!   weighted Gini score Σ_l w_l²/W (ties broken in a seeded random order). Binary splits
//!   never create the empty octants an 8-way split fills the node array with, and classify
//!   stays one compare per level; scoring the three attributes instead of picking one at
//!   random stops the tree from fragmenting its samples on an attribute the labels do not
//!   depend on (the incident direction when k_d is small), which left leaves "pure" by
//!   chance and cost held-out accuracy, at three passes over a node's samples at fit time
//!   only. Gini rather than "weight kept correct" because the latter is flat until a
//!   child's majority flips. Held-out accuracy is data-limited (the staircase's step is the
//!   training points' spacing): see tests/tests/spcbpt_classify.rs for measurements.
//!   Bounds start at (+∞, −∞) (the public code's "smallest positive float" start is a bug:
//!   it breaks for negative coordinates). Leaves take the weighted-majority label; a node
//!   without weight inherits its parent's label; depth is capped. The tree is a flat node
//!   array built with an explicit stack and read by a loop: no recursion anywhere.
//! * **Light-source bins** (section 7.2.1): vertices on the lights themselves are classified
//!   by (light, u, v) on a per-light grid, bins shared among lights ∝ power (each ≥ 1), ids
//!   following the tree's ids.

use alloc::vec;
use alloc::vec::Vec;

use super::features::{Attribute, SubpathFeature};
use crate::math::Vec2;
use crate::rng::{SampleStream, Stream};

/// The parameters of the distance of eq. 18.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistanceParams {
    /// σ², the squared spatial scale.
    pub sigma2: f32,
    /// Weight of the incident-direction term (paper: 0.05).
    pub k_d: f32,
}

impl DistanceParams {
    /// σ² = max(σ_x², σ_y², σ_z²) of `positions` (population variances, f64 sums; 0 for
    /// fewer than two finite points; non-finite positions are ignored).
    pub fn from_positions(positions: &[crate::math::Vec3], k_d: f32) -> Self {
        let mut n = 0.0f64;
        let mut mean = [0.0f64; 3];
        let mut m2 = [0.0f64; 3];
        for p in positions.iter().filter(|p| p.is_finite()) {
            // Welford's update, per axis.
            n += 1.0;
            for (axis, x) in [p.x, p.y, p.z].into_iter().enumerate() {
                let d = x as f64 - mean[axis];
                mean[axis] += d / n;
                m2[axis] += d * (x as f64 - mean[axis]);
            }
        }
        let sigma2 = if n < 2.0 { 0.0 } else { m2.iter().fold(0.0f64, |a, &b| a.max(b / n)) };
        Self { sigma2: sigma2 as f32, k_d }
    }

    /// d(a, b) of eq. 18.
    #[inline]
    pub fn distance(&self, a: &SubpathFeature, b: &SubpathFeature) -> f32 {
        let dp = a.position - b.position;
        dp.dot(dp) + self.sigma2 * (1.0 - a.normal.dot(b.normal)) + self.k_d * self.sigma2 * (1.0 - a.incident.dot(b.incident))
    }
}

/// `count` centroids drawn from `candidates` ∝ `weights`, without replacement,
/// deterministic in `seed`. Candidates with zero, negative or non-finite weight are never
/// drawn, so fewer than `count` come back when fewer have positive weight.
pub fn sample_centroids(candidates: &[SubpathFeature], weights: &[f32], count: usize, seed: u64) -> Vec<SubpathFeature> {
    let n = candidates.len().min(weights.len());
    // Efraimidis–Spirakis: key = ln(u)/w, keep the `count` largest keys.
    let mut keyed: Vec<(f64, u32)> = Vec::with_capacity(n);
    for (i, &w) in weights.iter().enumerate().take(n) {
        if !(w > 0.0 && w.is_finite()) {
            continue;
        }
        let mut rng = SampleStream::for_sample(seed, Stream::Preprocess, i as u32, 0x0ce7, 0);
        let u = rng.next_f64().max(f64::MIN_POSITIVE);
        keyed.push((crate::math::ln_f64(u) / w as f64, i as u32));
    }
    // Largest key first; ties by index so the result is a pure function of the inputs.
    let by_key = |a: &(f64, u32), b: &(f64, u32)| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1));
    if keyed.len() > count && count > 0 {
        keyed.select_nth_unstable_by(count - 1, by_key);
        keyed.truncate(count);
    }
    keyed.truncate(count);
    keyed.sort_unstable_by(by_key);
    keyed.into_iter().map(|(_, i)| candidates[i as usize]).collect()
}

/// κ of eq. 17 by brute force: the index of the centroid nearest to `x` (lowest index on
/// ties; 0 when there are no centroids).
pub fn nearest_centroid(centroids: &[SubpathFeature], params: &DistanceParams, x: &SubpathFeature) -> u32 {
    let mut best = (f32::INFINITY, 0u32);
    for (i, c) in centroids.iter().enumerate() {
        let d = params.distance(c, x);
        if d < best.0 {
            best = (d, i as u32);
        }
    }
    best.1
}

/// How a [`DecisionTree`] is grown.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeParams {
    /// A node becomes a leaf once this fraction of its weight is correctly labelled (0.99).
    pub accuracy: f32,
    /// Depth cap (root = depth 0).
    pub max_depth: u32,
    /// Nodes lighter than this are not split.
    pub min_leaf_weight: f32,
    /// Seed of the tie-breaking order among attributes.
    pub seed: u64,
}

impl Default for TreeParams {
    fn default() -> Self {
        Self { accuracy: 0.99, max_depth: 40, min_leaf_weight: 0.0, seed: 0 }
    }
}

const LEAF: u8 = u8::MAX;

/// One node: a leaf (`axis == LEAF`) holds `label`; an inner node sends a feature with
/// `x[axis] < threshold` to `first_child` and the rest to `first_child + 1`.
#[derive(Clone, Copy, Debug)]
struct Node {
    threshold: f32,
    first_child: u32,
    label: u32,
    axis: u8,
}

/// A decision tree reproducing subspace labels; a flat node array, read by a loop.
#[derive(Clone, Debug)]
pub struct DecisionTree {
    nodes: Vec<Node>,
}

/// Per-label weight histogram that clears only the labels it touched.
struct Histogram {
    weight: Vec<f64>,
}

impl Histogram {
    fn add(&mut self, label: u32, w: f64) {
        self.weight[label as usize] += w;
    }
    fn get(&self, label: u32) -> f64 {
        self.weight[label as usize]
    }
    fn clear(&mut self, label: u32) {
        self.weight[label as usize] = 0.0;
    }
}

impl DecisionTree {
    /// Fit a tree to `labels` (weighted by `weights`) of `samples`; mismatched lengths use
    /// the shortest, non-finite or negative weights count as 0. Deterministic in
    /// `params.seed`.
    pub fn fit(samples: &[SubpathFeature], labels: &[u32], weights: &[f32], params: &TreeParams) -> Self {
        let n = samples.len().min(labels.len()).min(weights.len());
        let weight_of = |i: u32| -> f64 {
            let w = weights[i as usize];
            if w > 0.0 && w.is_finite() { w as f64 } else { 0.0 }
        };
        let n_labels = labels[..n].iter().copied().max().map_or(1, |m| m as usize + 1);
        let mut hist = Histogram { weight: vec![0.0; n_labels] };
        let mut left = Histogram { weight: vec![0.0; n_labels] };
        let mut right = Histogram { weight: vec![0.0; n_labels] };
        let mut indices: Vec<u32> = (0..n as u32).collect();
        let mut nodes = vec![Node { threshold: 0.0, first_child: 0, label: 0, axis: LEAF }];
        // Work items: (node, start, end, depth, parent label).
        let mut stack: Vec<(u32, usize, usize, u32, u32)> = vec![(0, 0, n, 0, 0)];

        while let Some((node, start, end, depth, parent_label)) = stack.pop() {
            let members = &mut indices[start..end];
            // Step 1: weighted majority label and accuracy of this node.
            let mut total = 0.0f64;
            let mut best = (0.0f64, parent_label);
            for &i in members.iter() {
                hist.add(labels[i as usize], weight_of(i));
                total += weight_of(i);
            }
            for &i in members.iter() {
                let l = labels[i as usize];
                let w = hist.get(l);
                if w > best.0 || (w == best.0 && w > 0.0 && l < best.1) {
                    best = (w, l);
                }
            }
            for &i in members.iter() {
                hist.clear(labels[i as usize]);
            }
            let label = if total > 0.0 { best.1 } else { parent_label };
            nodes[node as usize].label = label;
            if total <= 0.0 || best.0 >= params.accuracy as f64 * total || depth >= params.max_depth || total < params.min_leaf_weight as f64 {
                continue;
            }

            // Step 2: candidate split per attribute: midpoint of its largest-extent axis.
            let mut order = Attribute::ALL;
            let mut rng = SampleStream::for_sample(params.seed, Stream::Preprocess, node, 0x7ee, depth);
            for k in (1..3).rev() {
                order.swap(k, rng.next_below(k as u32 + 1) as usize);
            }
            let mut chosen: Option<(f64, usize, f32)> = None;
            for attribute in order {
                let Some((axis, threshold)) = midpoint_split(members, samples, attribute) else {
                    continue;
                };
                // Score: Gini purity Σ_l w_l²/W of the two children (higher is purer).
                // Unlike "weight kept correct", it rewards splits that separate labels
                // before any child's majority changes, so irrelevant attributes lose.
                let (mut weight_left, mut weight_right) = (0.0f64, 0.0f64);
                for &i in members.iter() {
                    let w = weight_of(i);
                    if samples[i as usize].attribute_axis(axis) < threshold {
                        left.add(labels[i as usize], w);
                        weight_left += w;
                    } else {
                        right.add(labels[i as usize], w);
                        weight_right += w;
                    }
                }
                // Sum each label's square once: read it, then clear it.
                let (mut square_left, mut square_right) = (0.0f64, 0.0f64);
                let (mut has_left, mut has_right) = (false, false);
                for &i in members.iter() {
                    let l = labels[i as usize];
                    if samples[i as usize].attribute_axis(axis) < threshold {
                        square_left += left.get(l) * left.get(l);
                        has_left = true;
                    } else {
                        square_right += right.get(l) * right.get(l);
                        has_right = true;
                    }
                    left.clear(l);
                    right.clear(l);
                }
                if !(has_left && has_right) {
                    continue;
                }
                let purity = |square: f64, weight: f64| if weight > 0.0 { square / weight } else { 0.0 };
                let score = purity(square_left, weight_left) + purity(square_right, weight_right);
                if chosen.is_none_or(|c| score > c.0) {
                    chosen = Some((score, axis, threshold));
                }
            }
            let Some((_, axis, threshold)) = chosen else { continue };

            // Step 3: partition the members in place and queue the two children.
            let mut split = 0;
            for k in 0..members.len() {
                if samples[members[k] as usize].attribute_axis(axis) < threshold {
                    members.swap(k, split);
                    split += 1;
                }
            }
            let first_child = nodes.len() as u32;
            nodes[node as usize] = Node { threshold, first_child, label, axis: axis as u8 };
            nodes.push(Node { threshold: 0.0, first_child: 0, label, axis: LEAF });
            nodes.push(Node { threshold: 0.0, first_child: 0, label, axis: LEAF });
            stack.push((first_child + 1, start + split, end, depth + 1, label));
            stack.push((first_child, start, start + split, depth + 1, label));
        }
        nodes.shrink_to_fit();
        Self { nodes }
    }

    /// The subspace id of `x`: one comparison per level.
    #[inline]
    pub fn classify(&self, x: &SubpathFeature) -> u32 {
        let coords = x.to_array();
        let mut index = 0usize;
        loop {
            let Some(node) = self.nodes.get(index) else { return 0 };
            if node.axis == LEAF {
                return node.label;
            }
            // NaN goes right, like every value that is not below the threshold.
            let value = coords.get(node.axis as usize).copied().unwrap_or(0.0);
            let left = value < node.threshold;
            index = node.first_child as usize + (!left) as usize;
        }
    }

    /// Number of nodes (inner + leaves).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Depth of the deepest leaf (root = 0).
    pub fn depth(&self) -> u32 {
        let mut deepest = 0;
        let mut stack = vec![(0usize, 0u32)];
        while let Some((i, d)) = stack.pop() {
            let node = self.nodes[i];
            if node.axis == LEAF {
                deepest = deepest.max(d);
            } else {
                stack.push((node.first_child as usize, d + 1));
                stack.push((node.first_child as usize + 1, d + 1));
            }
        }
        deepest
    }

    /// Heap bytes held.
    pub fn size_bytes(&self) -> usize {
        self.nodes.capacity() * core::mem::size_of::<Node>()
    }

    /// The nodes as (axis, threshold, first child, label), axis 255 marking a leaf: what
    /// a stored model keeps ([`DecisionTree::from_raw_nodes`] reads it back).
    pub fn raw_nodes(&self) -> impl Iterator<Item = (u8, f32, u32, u32)> + '_ {
        self.nodes.iter().map(|n| (n.axis, n.threshold, n.first_child, n.label))
    }

    /// A tree from [`DecisionTree::raw_nodes`], refused unless it is one `classify` walks
    /// to a leaf in finitely many steps with a label below `labels`: every inner node's
    /// two children exist and come after it, axes name a feature coordinate, thresholds
    /// are not NaN. (A damaged file must give an error, not a loop or a wrong label.)
    pub fn from_raw_nodes(raw: &[(u8, f32, u32, u32)], labels: u32) -> Result<Self, &'static str> {
        if raw.is_empty() {
            return Err("a tree without nodes");
        }
        let mut nodes = Vec::with_capacity(raw.len());
        for (i, &(axis, threshold, first_child, label)) in raw.iter().enumerate() {
            if label >= labels {
                return Err("a tree label past the subspace count");
            }
            if axis != LEAF {
                if axis as usize >= crate::subspace::features::FEATURE_AXES {
                    return Err("a tree node splits on an axis the features do not have");
                }
                if threshold.is_nan() {
                    return Err("a tree node with a NaN threshold");
                }
                if first_child as usize <= i || first_child as usize + 1 >= raw.len() {
                    return Err("a tree node whose children are missing or come before it");
                }
            }
            nodes.push(Node { threshold, first_child, label, axis });
        }
        Ok(Self { nodes })
    }
}

/// (axis, threshold) splitting `attribute` at the centre of its largest extent among
/// `members`, or `None` when that attribute is constant (or non-finite) over them.
fn midpoint_split(members: &[u32], samples: &[SubpathFeature], attribute: Attribute) -> Option<(usize, f32)> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for &i in members {
        let v = samples[i as usize].attribute(attribute);
        for (k, x) in [v.x, v.y, v.z].into_iter().enumerate() {
            if x.is_finite() {
                lo[k] = lo[k].min(x);
                hi[k] = hi[k].max(x);
            }
        }
    }
    let mut best: Option<(f32, usize)> = None;
    for k in 0..3 {
        let extent = hi[k] - lo[k];
        if extent > 0.0 && extent.is_finite() && best.is_none_or(|b| extent > b.0) {
            best = Some((extent, k));
        }
    }
    let (extent, k) = best?;
    let threshold = lo[k] + 0.5 * extent;
    // Both sides must be non-empty: lo < threshold ≤ hi.
    (threshold > lo[k]).then_some((attribute as usize * 3 + k, threshold))
}

/// κ_L for vertices on the light sources themselves (section 7.2.1): a per-light grid
/// over the light's (u, v), with bins given to lights ∝ power.
///
/// A light with b bins is cut into r = ⌊√b⌋ rows of v; row i holds ⌊b/r⌋ cells of u, the
/// first b mod r rows one more — exactly b near-square cells for any b. Ids are
/// `first_id + (bins of earlier lights) + (cells of earlier rows) + column`.
#[derive(Clone, Debug)]
pub struct LightSourceBins {
    first_id: u32,
    /// `light_first[l]` = local id of light l's first bin; one extra entry = total.
    light_first: Vec<u32>,
    light_rows: Vec<u32>,
}

impl LightSourceBins {
    /// Bins for lights with the given powers; `total_bins` is raised to the number of
    /// lights if smaller. Non-finite or negative powers count as 0; all-zero powers share
    /// the bins equally. Remainders go to the largest fractional parts (lowest index on ties).
    pub fn new(light_powers: &[f32], total_bins: u32, first_id: u32) -> Self {
        let n = light_powers.len();
        let total = (total_bins as usize).max(n);
        let power: Vec<f64> = light_powers.iter().map(|&p| if p > 0.0 && p.is_finite() { p as f64 } else { 0.0 }).collect();
        let sum: f64 = power.iter().sum();
        let spare = total - n;
        // Each light 1 bin, plus its share of the spare ones.
        let share: Vec<f64> = power.iter().map(|&p| if sum > 0.0 { p / sum * spare as f64 } else { spare as f64 / n.max(1) as f64 }).collect();
        let mut bins: Vec<u32> = share.iter().map(|&s| 1 + s as u32).collect();
        let given: usize = bins.iter().map(|&b| b as usize).sum();
        let mut by_fraction: Vec<usize> = (0..n).collect();
        by_fraction.sort_by(|&a, &b| {
            let (fa, fb) = (share[a] - (share[a] as u32) as f64, share[b] - (share[b] as u32) as f64);
            fb.total_cmp(&fa).then(a.cmp(&b))
        });
        for &l in by_fraction.iter().take(total.saturating_sub(given)) {
            bins[l] += 1;
        }
        let mut light_first = Vec::with_capacity(n + 1);
        let mut acc = 0u32;
        for &b in &bins {
            light_first.push(acc);
            acc += b;
        }
        light_first.push(acc);
        let light_rows = bins.iter().map(|&b| (crate::math::sqrt(b as f32) as u32).clamp(1, b.max(1))).collect();
        Self { first_id, light_first, light_rows }
    }

    /// The subspace id of a light-source vertex on `light` at `uv` (clamped into [0,1)²;
    /// lights past the end use the last light). `first_id` when there are no lights.
    pub fn classify(&self, light: u32, uv: Vec2) -> u32 {
        let n = self.light_rows.len();
        if n == 0 {
            return self.first_id;
        }
        let l = (light as usize).min(n - 1);
        let bins = self.light_first[l + 1] - self.light_first[l];
        let rows = self.light_rows[l];
        let (base, extra) = (bins / rows, bins % rows);
        let cell = |x: f32, count: u32| -> u32 {
            // NaN and negatives → 0, ≥ 1 → last cell.
            let scaled = x * count as f32;
            if scaled >= 1.0 { (scaled as u32).min(count - 1) } else { 0 }
        };
        let row = cell(uv.y, rows);
        let row_cells = base + (row < extra) as u32;
        let row_first = row * base + row.min(extra);
        self.first_id + self.light_first[l] + row_first + cell(uv.x, row_cells)
    }

    /// Number of bins (ids `first_id..first_id + bin_count()`).
    pub fn bin_count(&self) -> u32 {
        self.light_first.last().copied().unwrap_or(0)
    }

    /// Bins given to `light` (0 out of range).
    pub fn bins_of(&self, light: u32) -> u32 {
        let l = light as usize;
        if l + 1 >= self.light_first.len() {
            return 0;
        }
        self.light_first[l + 1] - self.light_first[l]
    }

    /// Heap bytes held.
    pub fn size_bytes(&self) -> usize {
        (self.light_first.capacity() + self.light_rows.capacity()) * 4
    }

    /// (first id, first bin per light with the total last, rows per light): what a stored
    /// model keeps ([`LightSourceBins::from_parts`] reads it back).
    pub fn parts(&self) -> (u32, &[u32], &[u32]) {
        (self.first_id, &self.light_first, &self.light_rows)
    }

    /// Bins from [`LightSourceBins::parts`], refused unless they are bins `new` could
    /// have made for `lights` lights: `light_first` starts at 0 and grows by at least one
    /// bin per light, and each light's rows lie in 1..=its bins.
    pub fn from_parts(first_id: u32, light_first: Vec<u32>, light_rows: Vec<u32>, lights: usize) -> Result<Self, &'static str> {
        if light_rows.len() != lights || light_first.len() != lights + 1 || light_first.first() != Some(&0) {
            return Err("light-source bins for another number of lights");
        }
        for (l, &rows) in light_rows.iter().enumerate() {
            let bins = light_first[l + 1].saturating_sub(light_first[l]);
            if bins == 0 || rows == 0 || rows > bins {
                return Err("a light with no bins, or more rows than bins");
            }
        }
        first_id.checked_add(light_first[lights]).ok_or("light-source bin ids past 2^32")?;
        Ok(Self { first_id, light_first, light_rows })
    }
}
