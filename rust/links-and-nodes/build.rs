//! Sets the rpath of this crate's test binaries (unit and integration tests) and examples to
//! the libln that links-and-nodes-sys found (its `cargo:lib_dir`, seen here as
//! DEP_LN_LIB_DIR), so `cargo test` in a checkout runs against build/release/libln without
//! LD_LIBRARY_PATH.  The library itself is an rlib: programs using it choose their own.

fn main() {
    println!("cargo:rerun-if-env-changed=DEP_LN_LIB_DIR");
    if let Ok(dir) = std::env::var("DEP_LN_LIB_DIR") {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{dir}");
    }
}
