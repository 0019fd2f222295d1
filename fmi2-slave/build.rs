//! Rust bindings of the FMI 2.0 standard headers (`fmi-standard2/headers`,
//! 2-clause BSD, Modelica Association): the C types, constants and function
//! typedefs the exported functions are checked against, and `Fmi2Binding`
//! (libloading) for tests that load a built FMU.
//!
//! Generated here rather than taken from the `fmi-sys` crate: its `fmi2`
//! feature also compiles an importer-side logger whose `#[no_mangle]
//! callback_log` would be exported from every FMU library.

use std::path::PathBuf;

fn main() {
    let headers = PathBuf::from("fmi-standard2/headers");
    println!("cargo:rerun-if-changed={}", headers.display());
    let bindings = bindgen::Builder::default()
        .header(headers.join("fmi2Functions.h").to_string_lossy())
        .dynamic_link_require_all(false)
        .dynamic_library_name("Fmi2Binding")
        .allowlist_item("fmi2.*")
        .wrap_unsafe_ops(true)
        .generate()
        .expect("bindgen on the FMI 2.0 headers (needs libclang: Debian libclang-dev)");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR"));
    bindings
        .write_to_file(out.join("fmi2_bindings.rs"))
        .expect("writing the FMI 2.0 bindings");
}
