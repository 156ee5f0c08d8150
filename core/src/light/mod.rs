//! Lights (filled in by the lights work).
