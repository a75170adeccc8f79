//! Gives the shared library a SONAME, so programs linked against the installed
//! `libhybrid_rt.so` (scripts/install-c.sh) load the ABI they were built for. Before 1.0 a
//! minor release may break the ABI, so the SONAME carries major.minor (libhybrid_rt.so.0.1);
//! from 1.0 on, the major alone.
fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let major = std::env::var("CARGO_PKG_VERSION_MAJOR").unwrap_or_default();
    let minor = std::env::var("CARGO_PKG_VERSION_MINOR").unwrap_or_default();
    let target_os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if target_os == "linux" {
        let abi = if major == "0" { format!("0.{minor}") } else { major };
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libhybrid_rt.so.{abi}");
    }
}
