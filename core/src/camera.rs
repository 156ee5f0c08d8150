//! Pinhole camera (filled in by the camera work).
