//! The committed C header must be what cbindgen generates from the current source, and define
//! every task kind of the SDK. `HRT_BLESS=1 cargo test -p hybrid-rt-c --test header` rewrites it.

/// The header cbindgen generates from the current source.
fn generate() -> String {
    let dir = env!("CARGO_MANIFEST_DIR");
    let config = cbindgen::Config::from_file(format!("{dir}/cbindgen.toml")).expect("cbindgen.toml");
    let bindings = cbindgen::generate_with_config(dir, config).expect("cbindgen runs");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    String::from_utf8(generated).unwrap()
}

#[test]
fn header_is_current() {
    let dir = env!("CARGO_MANIFEST_DIR");
    let generated = generate();
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

/// The version is written once (the workspace's Cargo.toml): the Rust SDK, the C library and
/// the header agree with it.
#[test]
fn versions_agree() {
    let (major, minor, patch) = hybrid_rt::VERSION;
    let cargo = (
        env!("CARGO_PKG_VERSION_MAJOR").parse::<u32>().unwrap(),
        env!("CARGO_PKG_VERSION_MINOR").parse::<u32>().unwrap(),
        env!("CARGO_PKG_VERSION_PATCH").parse::<u32>().unwrap(),
    );
    assert_eq!((major, minor, patch), cargo, "the SDK's VERSION is the workspace version");
    assert_eq!(hybrid_rt_c::HRT_API_VERSION, (major << 22) | (minor << 12) | patch, "HRT_API_VERSION follows it");
    let header = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/include/hybrid_rt.h")).unwrap();
    assert!(header.contains("#define HRT_API_VERSION"), "the header defines HRT_API_VERSION");
}

/// Every task kind of the SDK has its C constant, `HRT_TASK_` and the kind's name in capitals,
/// with the SDK's value (each defined next to its task's C struct).
#[test]
fn every_task_kind_has_its_constant() {
    let header = generate();
    let missing: Vec<String> = hybrid_rt::TaskKind::ALL
        .iter()
        .map(|&k| format!("#define HRT_TASK_{} {}", k.name().to_uppercase(), k as u32))
        .filter(|define| !header.lines().any(|l| l == define))
        .collect();
    assert!(missing.is_empty(), "the header lacks {missing:?}");
}

/// Every C enum of the ABI is in the header with its values: cbindgen leaves out an enum no
/// function or struct names by type (the structs carry enums as u32), unless cbindgen.toml
/// exports it.
#[test]
fn every_enum_is_in_the_header() {
    let header = generate();
    let src = concat!(env!("CARGO_MANIFEST_DIR"), "/src");
    let mut missing = Vec::new();
    let mut stack = vec![std::path::PathBuf::from(src)];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            for line in text.lines() {
                if let Some(name) = line.strip_prefix("pub enum ").and_then(|r| r.strip_suffix(" {")) {
                    if !header.contains(&format!("enum {name} {{")) && !header.contains(&format!("enum {name}\n")) {
                        missing.push(name.to_string());
                    }
                }
            }
        }
    }
    assert!(missing.is_empty(), "the header lacks the enums {missing:?} (add them to cbindgen.toml's [export] include)");
}
