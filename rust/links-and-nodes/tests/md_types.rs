//! The hand-written test message types carry ln_generate's layout hash and size of their md
//! (tests/md): checked against the generator's C output, not against literals.

mod common;

use std::mem::size_of;

use common::{checkout, python, Counter, CounterOther};
use links_and_nodes::Message;

/// (LAYOUT_HASH, SIZE) of `prefix` in ln_generate's C header for `md`.
fn generated(md: &str, prefix: &str) -> (u64, usize) {
    let out = std::env::temp_dir().join(format!("ln-rust-md-{}-{prefix}.h", std::process::id()));
    let status = std::process::Command::new(python())
        .current_dir(checkout())
        .args(["-m", "ln_generate", "--md-dir"])
        .arg(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/md"))
        .arg("-o")
        .arg(&out)
        .arg(md)
        .status()
        .unwrap();
    assert!(status.success());
    let text = std::fs::read_to_string(&out).unwrap();
    let _ = std::fs::remove_file(&out);
    let value = |name: &str| -> String {
        let line = text
            .lines()
            .find(|l| l.starts_with(&format!("#define {prefix}_{name} ")))
            .unwrap_or_else(|| panic!("no {prefix}_{name}"));
        line.split_whitespace().nth(2).unwrap().to_string()
    };
    let hash = value("LAYOUT_HASH");
    let hex = hash.trim_start_matches("UINT64_C(0x").trim_end_matches(')');
    (
        u64::from_str_radix(hex, 16).unwrap(),
        value("SIZE").parse().unwrap(),
    )
}

#[test]
fn test_types_match_ln_generate() {
    assert_eq!(
        generated(Counter::MD_NAME, "RUST_TEST_COUNTER"),
        (Counter::LAYOUT_HASH, size_of::<Counter>())
    );
    assert_eq!(
        generated(CounterOther::MD_NAME, "RUST_TEST_COUNTER_OTHER"),
        (CounterOther::LAYOUT_HASH, size_of::<CounterOther>())
    );
}

/// The md names tests/generated/rust_test.rs holds (with their imports).
const GENERATED_MDS: [&str; 6] = [
    "rust_test/echo",
    "rust_test/echo_other",
    "robot/joint_state",
    "robot/plan_path",
    "robot/tool_state",
    "robot/set_gains",
];

/// tests/generated/rust_test.rs (used by the service tests and examples/interop.rs) is the
/// generator's output as it is now: regenerate it with the command printed on failure.
#[test]
fn committed_generated_types_are_fresh() {
    let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::env::temp_dir().join(format!("ln-rust-gen-{}.rs", std::process::id()));
    let status = std::process::Command::new(python())
        .current_dir(checkout())
        .args(["-m", "ln_generate", "--lang", "rust", "--md-dir"])
        .arg(manifest.join("tests/md"))
        .arg("-o")
        .arg(&out)
        .args(GENERATED_MDS)
        .status()
        .unwrap();
    assert!(status.success());
    let fresh = std::fs::read_to_string(&out).unwrap();
    let _ = std::fs::remove_file(&out);
    let committed = std::fs::read_to_string(manifest.join("tests/generated/rust_test.rs")).unwrap();
    assert!(
        fresh == committed,
        "tests/generated/rust_test.rs is stale; regenerate it (in rust/links-and-nodes):\n  \
         python -m ln_generate --lang rust --md-dir tests/md -o tests/generated/rust_test.rs {}",
        GENERATED_MDS.join(" ")
    );
}
