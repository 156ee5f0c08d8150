//! Materials (filled in by the materials work).
