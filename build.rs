//! The cdylib (the FMU binary) exports the fmi2* functions only: dependencies such as
//! fmi-sys define #[no_mangle] symbols (`callback_log`) that must not leak into the
//! importer's symbol namespace.

fn main() {
    println!("cargo:rerun-if-changed=src/fmi/exports.map");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        let dir = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default();
        println!("cargo:rustc-cdylib-link-arg=-Wl,--version-script={dir}/src/fmi/exports.map");
    }
}
