//! The serial training driver for Θ [SPCBPT section 7.3]: mini-batch Adam on the
//! MIS-aware loss of `loss.rs` over a shuffled order of the dataset.
//!
//! Each epoch draws a fresh permutation of the paths (Fisher–Yates driven by
//! `SampleStream(seed, Preprocess, epoch)`), cuts it into batches, and for every batch
//! (1) refreshes Γ from Θ, (2) accumulates the batch gradient, (3) normalises it by the
//! batch size and takes one Adam step. The batch mean keeps the step independent of the
//! batch size (Adam would mostly normalise it away anyway). The returned per-epoch loss
//! is the mean of w/F over the paths of the epoch, each evaluated with the Θ current when
//! its batch was processed — the usual "running" training loss.
//!
//! Hosts with threads reimplement this loop around [`super::loss_and_gradient`] /
//! [`super::loss_and_gradient_indexed`] on sub-ranges of a batch, summing per-thread
//! gradients in a fixed order so the result does not depend on the thread count.

use alloc::vec;
use alloc::vec::Vec;

use super::adam::{Adam, AdamParams};
use super::loss::{TrainingSet, loss_and_gradient_indexed};
use super::subspace_matrix::gamma_from_theta;
use crate::rng::{SampleStream, Stream};

/// Training hyper-parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrainParams {
    pub adam: AdamParams,
    /// Paths per Adam step (paper: 10 000).
    pub batch: usize,
    /// Passes over the dataset (paper: 2).
    pub epochs: u32,
    /// Uniform mixture m in Γ (paper: 0.1); training uses the same Γ the renderer samples.
    pub mixture: f32,
    /// Seed of the shuffles.
    pub seed: u64,
}

impl Default for TrainParams {
    fn default() -> Self {
        Self { adam: AdamParams::default(), batch: 10_000, epochs: 2, mixture: 0.1, seed: 0 }
    }
}

/// The batch size for `paths` paths: `max_batch`, or smaller so that `epochs` passes
/// take at least `steps` Adam steps. SPCBPT's paper trains |D| = 10⁶ paths in batches of
/// 10⁴ for 2 epochs: 200 steps. A dataset scaled down with the image (|D| = W·H here)
/// and cut into the same batches of 10⁴ takes a handful of steps, and Adam moves each
/// Θ by about α per step: with 8 steps Γ stays within a factor of about 2 of uniform,
/// whatever the data say. `steps = 0` or `epochs = 0` keeps `max_batch`.
pub fn batch_for_steps(paths: usize, max_batch: usize, epochs: u32, steps: u32) -> usize {
    let max_batch = max_batch.max(1);
    if steps == 0 || epochs == 0 || paths == 0 {
        return max_batch;
    }
    // Batches per epoch needed: ⌈steps / epochs⌉; each holds ⌊paths / that⌋ paths.
    let per_epoch = (steps as usize).div_ceil(epochs as usize);
    (paths / per_epoch).clamp(1, max_batch)
}

/// A permutation of 0..n, deterministic in (seed, epoch).
pub fn shuffled_order(n: usize, seed: u64, epoch: u32) -> Vec<u32> {
    let mut order: Vec<u32> = (0..n as u32).collect();
    let mut rng = SampleStream::for_sample(seed, Stream::Preprocess, 0x5eed_0000, 0, epoch);
    for i in (1..n).rev() {
        let j = (((rng.next_u64() >> 32) * (i as u64 + 1)) >> 32) as usize;
        order.swap(i, j);
    }
    order
}

/// Train Θ in place (eye-major, len n_light·n_eye, caller-initialised) and return the
/// per-epoch mean loss. A dimension mismatch or an empty set trains nothing.
pub fn train(set: &TrainingSet, theta: &mut [f32], n_light: usize, n_eye: usize, params: &TrainParams) -> Vec<f64> {
    let cells = n_light * n_eye;
    let mut losses = Vec::with_capacity(params.epochs as usize);
    if theta.len() < cells || cells == 0 {
        return losses;
    }
    let batch = params.batch.max(1);
    let mut gamma = vec![0.0f32; cells];
    let mut grad = vec![0.0f64; cells];
    let mut adam = Adam::new(cells, params.adam);
    for epoch in 0..params.epochs {
        let order = shuffled_order(set.len(), params.seed, epoch);
        let (mut epoch_loss, mut counted) = (0.0f64, 0usize);
        for chunk in order.chunks(batch) {
            // Refresh Γ for the current Θ, accumulate the batch gradient, step.
            gamma_from_theta(theta, n_light, n_eye, params.mixture, &mut gamma);
            grad.iter_mut().for_each(|g| *g = 0.0);
            let (loss, skipped) = loss_and_gradient_indexed(set, chunk, theta, &gamma, n_light, n_eye, params.mixture, &mut grad);
            let used = chunk.len() - skipped;
            epoch_loss += loss;
            counted += used;
            if used == 0 {
                continue;
            }
            let inv = 1.0 / used as f64;
            grad.iter_mut().for_each(|g| *g *= inv);
            adam.step(&mut theta[..cells], &grad);
        }
        losses.push(if counted > 0 { epoch_loss / counted as f64 } else { 0.0 });
    }
    losses
}

#[cfg(test)]
mod tests {
    use super::batch_for_steps;

    #[test]
    fn batches_shrink_to_keep_the_step_budget() {
        // The paper's scale: 10⁶ paths, batches of 10⁴, 2 epochs: 100 batches an epoch.
        assert_eq!(batch_for_steps(1_000_000, 10_000, 2, 200), 10_000);
        // Larger D keeps the batch (more steps than asked).
        assert_eq!(batch_for_steps(5_000_000, 10_000, 2, 200), 10_000);
        // ajar at 320×240: 33 065 paths with a contribution → 100 batches of 330.
        assert_eq!(batch_for_steps(33_065, 10_000, 2, 200), 330);
        // Odd step counts round the batches per epoch up; tiny sets go down to 1.
        assert_eq!(batch_for_steps(1_000, 10_000, 3, 200), 14);
        assert_eq!(batch_for_steps(10, 10_000, 2, 200), 1);
        // 0 steps, 0 epochs or an empty set keep the configured batch.
        assert_eq!(batch_for_steps(33_065, 10_000, 2, 0), 10_000);
        assert_eq!(batch_for_steps(33_065, 10_000, 0, 200), 10_000);
        assert_eq!(batch_for_steps(0, 0, 2, 200), 1);
    }
}
