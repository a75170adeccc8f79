//! The committed C header must be what cbindgen generates from the current source.
//! `HRT_BLESS=1 cargo test -p hybrid-rt-c --test header` rewrites it.
#[test]
fn header_is_current() {
    let dir = env!("CARGO_MANIFEST_DIR");
    let config = cbindgen::Config::from_file(format!("{dir}/cbindgen.toml")).expect("cbindgen.toml");
    let bindings = cbindgen::generate_with_config(dir, config).expect("cbindgen runs");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let generated = String::from_utf8(generated).unwrap();
    let path = format!("{dir}/include/hybrid_rt.h");
    if std::env::var("HRT_BLESS").is_ok_and(|v| v == "1") {
        std::fs::create_dir_all(format!("{dir}/include")).unwrap();
        std::fs::write(&path, &generated).unwrap();
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "sdk-c-api/include/hybrid_rt.h is stale: run `HRT_BLESS=1 cargo test -p hybrid-rt-c --test header` and commit it"
    );
}
