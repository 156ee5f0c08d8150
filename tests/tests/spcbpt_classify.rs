//! SPCBPT classification (`ember_core::subspace::classify`): the distance of eq. 18 and its
//! σ², centroid sampling ∝ contribution, the decision tree fitted to nearest-centroid
//! labels on a Cornell-box-like point set, and the light-source (u, v) bins.
//!
//! Statistical test: `centroids_are_drawn_in_proportion_to_weight` is the file's only one
//! (a χ² goodness-of-fit, α = 1e-3 per test, Šidák over 1). Everything else is
//! deterministic. Injected-bug checks (each done once, seen failing, reverted), in
//! `core/src/subspace/classify.rs`:
//! - bug A, "centroids drawn uniformly" (key `ln(u)` without `/w`): the χ² test failed
//!   (χ² = 5.4e4, p = 0).
//! - bug B, "bounds start at the smallest positive float" (the public code's bug: `lo`
//!   initialised to `f32::MIN_POSITIVE` instead of +∞): thresholds on the box's negative
//!   half went wrong: training accuracy fell to 0.69 and the held-out test failed.
//! - bug C, "leaf takes the first sample's label" instead of the weighted majority:
//!   `tree_leaves_take_the_weighted_majority_…` failed (the held-out test did not: its
//!   leaves are ≥ 99% pure, so the first label is almost always the majority).
//! - bug D, "row offset without the extra cells of earlier rows" (`row * base`):
//!   `light_bins_cover_every_id_exactly_once` failed (a 7-bin light reached 6 ids).

use ember_core::Vec2;
use ember_core::Vec3;
use ember_core::rng::{SampleStream, Stream};
use ember_core::subspace::classify::{DecisionTree, DistanceParams, LightSourceBins, TreeParams, nearest_centroid, sample_centroids};
use ember_core::subspace::features::SubpathFeature;
use ember_tests::chi2::sidak;
use ember_tests::stats::chi2_survival;

fn rng(index: u32, sample: u32) -> SampleStream {
    SampleStream::for_sample(0xc1a55, Stream::Aux, index, sample, 0)
}

/// An axis-aligned face: origin, two edge vectors, outward normal into the box.
struct Face {
    origin: Vec3,
    u: Vec3,
    v: Vec3,
    normal: Vec3,
}

/// The Cornell-like scene: the [-1,1]³ box without its front wall, plus a short block.
fn cornell_faces() -> Vec<Face> {
    let f = |o: [f32; 3], u: [f32; 3], v: [f32; 3], n: [f32; 3]| Face { origin: Vec3::from(o), u: Vec3::from(u), v: Vec3::from(v), normal: Vec3::from(n) };
    vec![
        f([-1.0, -1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0], [0.0, 1.0, 0.0]), // floor
        f([-1.0, 1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0], [0.0, -1.0, 0.0]), // ceiling
        f([-1.0, -1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 1.0]), // back
        f([-1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0], [1.0, 0.0, 0.0]), // left
        f([1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0], [-1.0, 0.0, 0.0]), // right
        f([-0.6, -0.3, -0.5], [0.5, 0.0, 0.0], [0.0, 0.0, 0.5], [0.0, 1.0, 0.0]), // block top
        f([-0.6, -1.0, 0.0], [0.5, 0.0, 0.0], [0.0, 0.7, 0.0], [0.0, 0.0, 1.0]),  // block front
        f([-0.1, -1.0, -0.5], [0.0, 0.7, 0.0], [0.0, 0.0, 0.5], [1.0, 0.0, 0.0]), // block right
    ]
}

/// `n` sub-path end vertices spread over the faces ∝ area, incident directions uniform
/// over the normal's hemisphere, and a contribution weight (brighter near the ceiling).
fn cornell_points(n: u32, stream: u32) -> (Vec<SubpathFeature>, Vec<f32>) {
    let faces = cornell_faces();
    let areas: Vec<f32> = faces.iter().map(|f| f.u.cross(f.v).length()).collect();
    let total: f32 = areas.iter().sum();
    let mut points = Vec::with_capacity(n as usize);
    let mut weights = Vec::with_capacity(n as usize);
    for i in 0..n {
        let mut r = rng(i, stream);
        let mut pick = r.next_f32() * total;
        let mut face = &faces[faces.len() - 1];
        for (f, &a) in faces.iter().zip(&areas) {
            if pick < a {
                face = f;
                break;
            }
            pick -= a;
        }
        let position = face.origin + face.u * r.next_f32() + face.v * r.next_f32();
        // Half the vertices are first bounces seen from the camera (incident toward it),
        // half deeper bounces (incident uniform over the normal's hemisphere).
        let incident = if r.next_f32() < 0.5 {
            (Vec3::new(0.0, 0.0, 3.5) - position).normalize()
        } else {
            loop {
                let d = Vec3::new(2.0 * r.next_f32() - 1.0, 2.0 * r.next_f32() - 1.0, 2.0 * r.next_f32() - 1.0);
                let len = d.length();
                if len > 1e-3 && len <= 1.0 {
                    let d = d / len;
                    break if d.dot(face.normal) < 0.0 { -d } else { d };
                }
            }
        };
        points.push(SubpathFeature { position, normal: face.normal, incident });
        weights.push(0.1 + (position.y + 1.0) * r.next_f32());
    }
    (points, weights)
}

#[test]
fn sigma2_is_the_largest_axis_variance_and_distance_is_eq18() {
    let positions: Vec<Vec3> = (0..1000)
        .map(|i| {
            let mut r = rng(i, 1);
            Vec3::new(r.next_f32(), 3.0 * r.next_f32() - 7.0, 0.5 * r.next_f32())
        })
        .collect();
    let params = DistanceParams::from_positions(&positions, 0.05);
    let n = positions.len() as f64;
    let mean_y = positions.iter().map(|p| p.y as f64).sum::<f64>() / n;
    let var_y = positions.iter().map(|p| (p.y as f64 - mean_y).powi(2)).sum::<f64>() / n;
    assert!((params.sigma2 as f64 - var_y).abs() < 1e-5 * var_y, "σ² {} vs var_y {var_y}", params.sigma2);
    assert_eq!(params.k_d, 0.05);
    assert_eq!(DistanceParams::from_positions(&[], 0.05).sigma2, 0.0);
    let params = DistanceParams { sigma2: 2.0, k_d: 0.5 };
    let a = SubpathFeature::new(Vec3::new(0.0, 0.0, 0.0), Vec3::Y, Vec3::X);
    let b = SubpathFeature::new(Vec3::new(1.0, 2.0, 0.0), Vec3::X, -Vec3::X);
    // 5 + 2·(1 − 0) + 0.5·2·(1 + 1) = 9.
    assert!((params.distance(&a, &b) - 9.0).abs() < 1e-6);
    assert_eq!(params.distance(&a, &a), 0.0);
}

/// Bug A: the first centroid is drawn ∝ weight (χ² over many seeds); zero weights never.
#[test]
fn centroids_are_drawn_in_proportion_to_weight() {
    let weights = [1.0f32, 2.0, 3.0, 4.0, 0.0, 10.0, 0.5];
    let candidates: Vec<SubpathFeature> = (0..weights.len()).map(|i| SubpathFeature::new(Vec3::splat(i as f32), Vec3::Y, Vec3::ZERO)).collect();
    let draws = 40_000u64;
    let mut counts = [0u64; 7];
    for seed in 0..draws {
        let c = sample_centroids(&candidates, &weights, 1, seed);
        counts[c[0].position.x as usize] += 1;
    }
    assert_eq!(counts[4], 0, "a zero-weight candidate was drawn");
    let total: f64 = weights.iter().map(|&w| w as f64).sum();
    let mut statistic = 0.0;
    let mut dof = 0.0;
    for (i, &w) in weights.iter().enumerate() {
        if w > 0.0 {
            let expected = draws as f64 * w as f64 / total;
            statistic += (counts[i] as f64 - expected).powi(2) / expected;
            dof += 1.0;
        }
    }
    let p = chi2_survival(statistic, dof - 1.0);
    assert!(p > sidak(1e-3, 1), "χ² = {statistic}, p = {p}, counts {counts:?}");

    // Without replacement: all six positive-weight candidates, no duplicates, none extra.
    let all = sample_centroids(&candidates, &weights, 10, 3);
    assert_eq!(all.len(), 6);
    let mut ids: Vec<u32> = all.iter().map(|c| c.position.x as u32).collect();
    ids.sort();
    assert_eq!(ids, vec![0, 1, 2, 3, 5, 6]);
    assert_eq!(sample_centroids(&candidates, &weights, 3, 9), sample_centroids(&candidates, &weights, 3, 9));
}

#[test]
fn nearest_centroid_is_the_argmin_with_lowest_index_on_ties() {
    let params = DistanceParams { sigma2: 1.0, k_d: 0.05 };
    let c = |x: f32| SubpathFeature::new(Vec3::new(x, 0.0, 0.0), Vec3::Y, Vec3::ZERO);
    let centroids = [c(0.0), c(2.0), c(2.0), c(-3.0)];
    assert_eq!(nearest_centroid(&centroids, &params, &c(1.9)), 1);
    assert_eq!(nearest_centroid(&centroids, &params, &c(-2.0)), 3);
    assert_eq!(nearest_centroid(&centroids, &params, &c(0.9)), 0);
    assert_eq!(nearest_centroid(&[], &params, &c(0.9)), 0);
}

/// Bugs B and C: the tree reproduces nearest-centroid labels on held-out samples.
#[test]
fn tree_reproduces_nearest_centroid_labels_on_held_out_points() {
    let (candidates, candidate_weights) = cornell_points(20_000, 10);
    let centroids = sample_centroids(&candidates, &candidate_weights, 32, 7);
    assert_eq!(centroids.len(), 32);
    let positions: Vec<Vec3> = candidates.iter().map(|c| c.position).collect();
    let params = DistanceParams::from_positions(&positions, 0.05);
    let label = |x: &SubpathFeature| nearest_centroid(&centroids, &params, x);

    let (train, train_w) = cornell_points(200_000, 11);
    let labels: Vec<u32> = train.iter().map(label).collect();
    let tree = DecisionTree::fit(&train, &labels, &train_w, &TreeParams { seed: 5, ..TreeParams::default() });

    let weighted_accuracy = |points: &[SubpathFeature], weights: &[f32]| -> f64 {
        let (mut right, mut total) = (0.0f64, 0.0f64);
        for (p, &w) in points.iter().zip(weights) {
            total += w as f64;
            if tree.classify(p) == label(p) {
                right += w as f64;
            }
        }
        right / total
    };
    let (held_out, held_out_w) = cornell_points(20_000, 12);
    let train_accuracy = weighted_accuracy(&train, &train_w);
    let held_out_accuracy = weighted_accuracy(&held_out, &held_out_w);
    println!(
        "tree: {} nodes, depth {}, {} bytes; weighted accuracy train {train_accuracy:.4}, held-out {held_out_accuracy:.4}",
        tree.node_count(),
        tree.depth(),
        tree.size_bytes()
    );
    assert!(train_accuracy >= 0.985, "training accuracy {train_accuracy}");
    assert!(held_out_accuracy >= 0.95, "held-out accuracy {held_out_accuracy}");

    // Classify cost (printed only: timing asserts would be flaky on shared machines).
    let start = std::time::Instant::now();
    let mut checksum = 0u64;
    for _ in 0..10 {
        for p in &held_out {
            checksum += tree.classify(std::hint::black_box(p)) as u64;
        }
    }
    let per = start.elapsed().as_secs_f64() * 1e9 / (10 * held_out.len()) as f64;
    println!("tree classify: {per:.1} ns per sub-path (checksum {checksum})");

    // Determinism: the same inputs give the same tree.
    let again = DecisionTree::fit(&train, &labels, &train_w, &TreeParams { seed: 5, ..TreeParams::default() });
    assert_eq!(again.node_count(), tree.node_count());
    assert!(held_out.iter().all(|p| again.classify(p) == tree.classify(p)));
}

/// Bug C: leaves take the weighted majority; degenerate inputs make leaves, not panics.
#[test]
fn tree_leaves_take_the_weighted_majority_and_degenerate_input_is_safe() {
    let same = SubpathFeature::new(Vec3::new(-0.5, -0.5, -0.5), Vec3::Y, Vec3::ZERO);
    // Identical features, conflicting labels: one leaf with the heavier label (7, not 2).
    let samples = vec![same; 5];
    let labels = [2, 7, 2, 7, 2];
    let weights = [1.0, 3.0, 1.0, 3.0, 1.0];
    let tree = DecisionTree::fit(&samples, &labels, &weights, &TreeParams::default());
    assert_eq!(tree.node_count(), 1);
    assert_eq!(tree.classify(&same), 7);
    // No samples, or no weight: a single leaf with label 0.
    assert_eq!(DecisionTree::fit(&[], &[], &[], &TreeParams::default()).classify(&same), 0);
    let zero = DecisionTree::fit(&samples, &labels, &[0.0, f32::NAN, -1.0, 0.0, 0.0], &TreeParams::default());
    assert_eq!(zero.classify(&same), 0);
    // Two clusters on negative coordinates split cleanly; the depth cap holds.
    let a = SubpathFeature::new(Vec3::new(-3.0, -2.0, -1.0), Vec3::Y, Vec3::ZERO);
    let b = SubpathFeature::new(Vec3::new(-2.0, -2.0, -1.0), Vec3::Y, Vec3::ZERO);
    let tree = DecisionTree::fit(&[a, b, a, b], &[4, 9, 4, 9], &[1.0; 4], &TreeParams::default());
    assert_eq!((tree.classify(&a), tree.classify(&b)), (4, 9));
    assert_eq!(tree.node_count(), 3);
    let capped = DecisionTree::fit(&[a, b], &[4, 9], &[1.0; 2], &TreeParams { max_depth: 0, ..TreeParams::default() });
    assert_eq!(capped.node_count(), 1);
    // NaN features classify without panicking.
    let nan = SubpathFeature::new(Vec3::splat(f32::NAN), Vec3::splat(f32::NAN), Vec3::ZERO);
    assert!([4, 9].contains(&tree.classify(&nan)));
}

/// Bug D: every id in [first_id, first_id + bin_count) is reached, each by one light, and
/// lights get bins ∝ power (each ≥ 1).
#[test]
fn light_bins_cover_every_id_exactly_once() {
    let configs: Vec<(Vec<f32>, u32)> = vec![
        (vec![1.0], 1),
        (vec![1.0], 7),
        (vec![1.0], 200),
        (vec![1.0, 1.0, 1.0], 13),
        (vec![10.0, 1.0, 0.1], 200),
        (vec![0.0, 0.0], 9),
        (vec![5.0, f32::NAN, -1.0, 2.0], 3),
        ((0..20).map(|i| 1.0 + i as f32).collect(), 211),
    ];
    for (powers, total) in configs {
        let first_id = 1000;
        let bins = LightSourceBins::new(&powers, total, first_id);
        let count = bins.bin_count();
        assert_eq!(count, total.max(powers.len() as u32), "{powers:?}");
        let mut owner = vec![u32::MAX; count as usize];
        let grid = 256;
        for light in 0..powers.len() as u32 {
            assert!(bins.bins_of(light) >= 1);
            let mut seen = std::collections::BTreeSet::new();
            for i in 0..grid {
                for j in 0..grid {
                    let uv = Vec2::new((i as f32 + 0.5) / grid as f32, (j as f32 + 0.5) / grid as f32);
                    let id = bins.classify(light, uv);
                    assert!((first_id..first_id + count).contains(&id), "id {id} out of range");
                    let slot = &mut owner[(id - first_id) as usize];
                    assert!(*slot == u32::MAX || *slot == light, "id {id} shared by lights {} and {light}", *slot);
                    *slot = light;
                    seen.insert(id);
                }
            }
            assert_eq!(seen.len() as u32, bins.bins_of(light), "light {light} of {powers:?}");
        }
        assert!(owner.iter().all(|&o| o != u32::MAX), "unreached ids for {powers:?}, {total}");
        // Proportional shares (largest remainder: within one bin of 1 + share of the rest).
        let clean: Vec<f64> = powers.iter().map(|&p| if p > 0.0 && p.is_finite() { p as f64 } else { 0.0 }).collect();
        let sum: f64 = clean.iter().sum();
        if sum > 0.0 {
            let spare = (count - powers.len() as u32) as f64;
            for (l, &p) in clean.iter().enumerate() {
                let ideal = 1.0 + spare * p / sum;
                assert!((bins.bins_of(l as u32) as f64 - ideal).abs() < 1.0 + 1e-9, "light {l}: {} vs {ideal}", bins.bins_of(l as u32));
            }
        }
        // Out-of-range input is clamped, never panics.
        for uv in [Vec2::new(-1.0, 2.0), Vec2::new(f32::NAN, 1.0), Vec2::new(1.0, 1.0)] {
            let id = bins.classify(powers.len() as u32 + 3, uv);
            assert!((first_id..first_id + count).contains(&id));
        }
    }
    assert_eq!(LightSourceBins::new(&[], 10, 5).bin_count(), 0);
}
