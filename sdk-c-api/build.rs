//! Gives the installed shared library a SONAME, so programs linked against the installed
//! `libhybrid_rt.so` (scripts/install-c.sh, which sets `HRT_C_SONAME=1`) load the ABI they were
//! built for. Before 1.0 a minor release may break the ABI, so the SONAME carries major.minor
//! (libhybrid_rt.so.0.1); from 1.0 on, the major alone.
//!
//! A plain `cargo build` gives none: the build tree holds `libhybrid_rt_c.so` and no file of
//! the SONAME's name, so a program linked against the build tree would record a name it
//! cannot load. Without a SONAME it records the file it was linked with, and loads.
fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=HRT_C_SONAME");
    let major = std::env::var("CARGO_PKG_VERSION_MAJOR").unwrap_or_default();
    let minor = std::env::var("CARGO_PKG_VERSION_MINOR").unwrap_or_default();
    let target_os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if target_os == "linux" && std::env::var_os("HRT_C_SONAME").is_some_and(|v| v == "1") {
        let abi = if major == "0" { format!("0.{minor}") } else { major };
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libhybrid_rt.so.{abi}");
    }
}
