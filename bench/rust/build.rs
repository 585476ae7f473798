//! Generates the benchmark's message types (bench/md/lnbench/sample_*) with
//! `ln_generate --lang rust` through links-and-nodes-build, and sets the binaries' rpath to
//! the libln that links-and-nodes-sys found.

use std::env;
use std::ffi::OsString;
use std::path::PathBuf;

const MESSAGES: [&str; 4] = [
    "lnbench/sample_64",
    "lnbench/sample_4k",
    "lnbench/sample_1m",
    "lnbench/sample_4m",
];

fn main() {
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    let mut generator = links_and_nodes_build::Generator::new().md_dir(manifest.join("../md"));
    for name in MESSAGES {
        generator = generator.message(name);
    }
    // The checkout's own ln_generate (its .venv), unless LN_GENERATE says otherwise.
    let venv_python = manifest.join("../../.venv/bin/python");
    if env::var_os("LN_GENERATE").is_none() && venv_python.exists() {
        let argv: [OsString; 3] = [venv_python.into(), "-m".into(), "ln_generate".into()];
        generator = generator.command(argv);
    }
    if let Err(e) = generator.generate(out.join("lnbench.rs")) {
        panic!("{e}");
    }
    println!("cargo:rerun-if-env-changed=DEP_LN_LIB_DIR");
    if let Ok(dir) = env::var("DEP_LN_LIB_DIR") {
        println!("cargo:rustc-link-arg-bins=-Wl,-rpath,{dir}");
    }
}
