//! `ember-formats`: the files around the core — the Mitsuba 3 XML reader ([`mitsuba`],
//! with its OBJ and PLY meshes and bitmap textures), EXR and PNG images ([`image_io`]), Radiance RGBE and PFM decoding
//! ([`float_images`]),
//! bounded reads of inputs ([`files`]), image error metrics ([`metrics`]) and the record of
//! error against run time ([`error_time`]); what the
//! command line and a later Python package share.
//!
//! What code here may do: read and write files, and report a long scene load on stderr.
//! What it may not: start threads or render (that is `ember-host`), or parse command
//! lines (`ember-cli`); it depends on the core alone.

pub mod error_time;
pub mod files;
pub mod float_images;
pub mod image_io;
pub mod metrics;
pub mod mitsuba;
