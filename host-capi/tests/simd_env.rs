//! The C library's scenes take the ray queries' instruction set from `EMBER_SIMD`, as
//! `ember render` does: a name the machine does not offer is refused when the scene is
//! created, naming the variable. Each case runs in a child process of this test binary
//! (the environment is process-wide). Seen failing with `SceneData::new` not reading the
//! variable (the bogus name was accepted).

use std::process::Command;

use ember_capi::{EmberStatus, SceneData};

/// The child's side: create a scene under the environment the parent gave it.
#[test]
fn child_creates_a_scene() {
    let Ok(expect) = std::env::var("EMBER_SIMD_TEST_EXPECT") else { return };
    let result = SceneData::builtin("cornell-box", 8, 8);
    match expect.as_str() {
        "ok" => assert!(result.is_ok(), "{:?}", result.err()),
        _ => {
            let e = result.expect_err("refused");
            assert_eq!(e.status, EmberStatus::InvalidArgument);
            assert!(e.message.contains("EMBER_SIMD: unknown SIMD instruction set 'avx1024'"), "{}", e.message);
        }
    }
}

#[test]
fn ember_simd_is_obeyed_and_checked() {
    let base = ember_host::accel::Isa::offered()[0].name();
    for (value, expect) in [("avx1024", "refused"), (base, "ok"), ("", "ok")] {
        let out = Command::new(std::env::current_exe().unwrap())
            .args(["--exact", "child_creates_a_scene", "--nocapture"])
            .env("EMBER_SIMD", value)
            .env("EMBER_SIMD_TEST_EXPECT", expect)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success() && text.contains("1 passed"), "EMBER_SIMD={value:?}: {text}{}", String::from_utf8_lossy(&out.stderr));
    }
}
