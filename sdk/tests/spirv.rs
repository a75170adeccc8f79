//! The SPIR-V shipped in `sdk/spirv/` is what the GLSL in `shaders/` (the source of truth)
//! compiles to: every shader has its SPIR-V, made from the current source (by hash), and no
//! SPIR-V is left over. `HRT_BLESS=1 cargo test -p hybrid-rt --features compile-shaders --test spirv`
//! (the feature: so a new shader's constant exists before its SPIR-V is shipped) regenerates it with
//! glslangValidator (and validates it with spirv-val).
#[path = "../build/spirv.rs"]
mod spirv;

use std::path::PathBuf;

#[test]
fn shipped_spirv_is_made_from_the_current_glsl() {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let shaders = manifest.join("../shaders");
    let out = manifest.join("spirv");
    let sources = spirv::sources(&shaders);
    assert!(!sources.is_empty(), "no GLSL in {} (run from the repository)", shaders.display());
    let hashes: Vec<(String, u64)> =
        sources.iter().map(|s| (spirv::spv_name(s), spirv::source_hash(s, &shaders.join("include")))).collect();
    let listing: String = hashes.iter().map(|(n, h)| format!("{n} {h:016x}\n")).collect();
    if std::env::var("HRT_BLESS").is_ok_and(|v| v == "1") {
        let compiler = std::env::var("GLSLANG_VALIDATOR").unwrap_or_else(|_| "glslangValidator".into());
        let _ = std::fs::remove_dir_all(&out);
        std::fs::create_dir_all(&out).unwrap();
        for src in &sources {
            let spv = out.join(spirv::spv_name(src));
            spirv::compile(&compiler, src, &spv).unwrap();
            spirv::validate(&spv).unwrap();
        }
        std::fs::write(out.join("SOURCES"), listing).unwrap();
        return;
    }
    let recorded = std::fs::read_to_string(out.join("SOURCES")).unwrap_or_default();
    assert!(
        recorded == listing,
        "sdk/spirv is stale against shaders/: run `HRT_BLESS=1 cargo test -p hybrid-rt --features compile-shaders --test spirv` and commit it\n\
         recorded:\n{recorded}\ncurrent:\n{listing}"
    );
    let mut shipped: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".spv"))
        .collect();
    shipped.sort();
    let expected: Vec<String> = hashes.into_iter().map(|(n, _)| n).collect();
    assert_eq!(shipped, expected, "one shipped SPIR-V per shader, none left over");
    for name in &shipped {
        let bytes = std::fs::read(out.join(name)).unwrap();
        assert!(bytes.len() > 20 && bytes[..4] == [0x03, 0x02, 0x23, 0x07], "{name} is SPIR-V");
    }
}
