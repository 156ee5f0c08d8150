//! Placeholder: builds the estimator a `render` command asks for. The lead replaces
//! this file with the wiring of the core's scene and estimators.

use crate::cli::RenderArgs;
use crate::driver::PassRenderer;

/// The renderer for `args` (scene, estimator, resolution, depth, seed).
pub fn make_renderer(_args: &RenderArgs) -> Result<Box<dyn PassRenderer>, String> {
    Err("estimators not wired yet".into())
}
