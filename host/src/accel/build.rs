//! obvhs's binary hierarchy built without a clock, on every target.
//!
//! obvhs's build helpers (`bvh2::builder::build_bvh2`, `cwbvh::builder::build_cwbvh`
//! and their `…_from_tris` forms) time themselves with `std::time::Instant::now()`,
//! which traps in the browser (`wasm32-unknown-unknown`: "time not implemented on this
//! platform"). [`build_bvh2_without_clock`] runs the steps of obvhs 0.4's `build_bvh2`
//! in the same order with the same parameters, and no clock: so the CLI, the C library
//! and the browser build the same hierarchy from the same boxes, and a native image is
//! the one obvhs's helper gave (`host-cli/tests/image_hashes.rs` pins it).

use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::leaf_collapser::collapse;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::ploc::PlocBuilder;

/// obvhs's `build_bvh2(boxes, config, _)` step for step, without its `Instant` timing:
/// the PLOC build over the boxes (primitive i is box i), reinsertion, the leaf collapse
/// to at most `config.max_prims_per_leaf` primitives, reinsertion again with the
/// post-collapse batch ratio; in builds with debug assertions, obvhs's validation, as
/// its helper does. `config.pre_split` is ignored, as `build_bvh2` ignores it.
pub fn build_bvh2_without_clock(boxes: &[Aabb], config: BvhBuildParams) -> Bvh2 {
    // Build the hierarchy.
    let indices = (0..boxes.len() as u32).collect::<Vec<_>>();
    let mut bvh =
        PlocBuilder::with_capacity(boxes.len()).build(config.ploc_search_distance, boxes, indices, config.sort_precision, config.search_depth_threshold);
    // Improve it, collapse leaves, improve again.
    let mut reinsertion = ReinsertionOptimizer::default();
    reinsertion.run(&mut bvh, config.reinsertion_batch_ratio, None);
    collapse(&mut bvh, config.max_prims_per_leaf.clamp(1, 255), config.collapse_traversal_cost);
    reinsertion.run(&mut bvh, config.reinsertion_batch_ratio * config.post_collapse_reinsertion_batch_ratio_multiplier, None);
    #[cfg(debug_assertions)]
    {
        bvh.validate(boxes, false, config.pre_split);
    }
    bvh
}
