//! `include/ember.h` is what cbindgen generates from `src/ffi.rs` now: a change to the
//! C API without the header fails here. `EMBER_UPDATE_HEADER=1` rewrites the header.

use std::path::PathBuf;

#[test]
fn the_header_is_current() {
    let crate_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let mut generated = Vec::new();
    cbindgen::Builder::new().with_crate(&crate_dir).with_config(config).generate().expect("cbindgen parses src/").write(&mut generated);
    let path = crate_dir.join("include/ember.h");
    if std::env::var_os("EMBER_UPDATE_HEADER").is_some() {
        std::fs::write(&path, &generated).expect("write the header");
    }
    let committed = std::fs::read(&path).unwrap_or_default();
    assert!(committed == generated, "include/ember.h is stale: run `EMBER_UPDATE_HEADER=1 cargo test --release -p ember-capi --test header` and commit it");
}
