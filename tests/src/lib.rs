//! Shared statistical test kit.
