//! Generates the Rust types of the robot mds (the checkout's message_definitions, which
//! ln_generate searches by default) into $OUT_DIR/robot.rs, as a user's crate would, and
//! gives the programs an rpath to the checkout's libln ($LN_LIBRARY_PATH, else
//! build/release/libln; an installed libln needs none).

use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let generated = links_and_nodes_build::Generator::new()
        .message("robot/joint_state")
        .message("robot/command")
        .message("robot/set_gains")
        .generate(out.join("robot.rs"));
    if let Err(e) = generated {
        panic!("{e}");
    }
    println!("cargo:rerun-if-env-changed=LN_LIBRARY_PATH");
    let checkout = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../build/release/libln");
    let lib_dir = std::env::var_os("LN_LIBRARY_PATH")
        .map(PathBuf::from)
        .or_else(|| {
            checkout
                .is_dir()
                .then(|| checkout.canonicalize().unwrap_or(checkout))
        });
    if let Some(dir) = lib_dir {
        println!("cargo:rustc-link-arg-bins=-Wl,-rpath,{}", dir.display());
    }
}
