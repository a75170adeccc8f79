//! Shared by build.rs and tests/spirv.rs: the SDK's shaders, how each is compiled to SPIR-V,
//! and the hash that says whether the shipped SPIR-V (`sdk/spirv/`) was made from the current
//! GLSL (`shaders/`, the source of truth).
#![allow(dead_code)]
use std::path::{Path, PathBuf};
use std::process::Command;

/// Shader stages by file extension.
pub const STAGES: &[&str] = &["rgen", "rmiss", "rchit", "rahit", "comp"];

/// The shader sources under `dir` (not its include folder), sorted.
pub fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> =
        std::fs::read_dir(dir).map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect()).unwrap_or_default();
    v.retain(|p| p.extension().and_then(|e| e.to_str()).is_some_and(|e| STAGES.contains(&e)));
    v.sort();
    v
}

/// Ray-tracing stages are SPIR-V 1.4 (what VK_KHR_ray_tracing_pipeline needs); compute
/// shaders SPIR-V 1.5. (SPIR-V 1.6 states the workgroup size as LocalSizeId, which needs the
/// `maintenance4` feature: wgpu, and so Bevy, leave it off on the devices they create.)
pub fn target_env(src: &Path) -> &'static str {
    if src.extension().is_some_and(|e| e == "comp") {
        "spirv1.5"
    } else {
        "spirv1.4"
    }
}

/// The file name of a shader's SPIR-V ("ao.rgen" -> "ao.rgen.spv") and its Rust constant
/// ("AO_RGEN").
pub fn spv_name(src: &Path) -> String {
    format!("{}.spv", src.file_name().and_then(|f| f.to_str()).unwrap_or_default())
}

pub fn constant_name(src: &Path) -> String {
    src.file_name().and_then(|f| f.to_str()).unwrap_or_default().replace('.', "_").to_uppercase()
}

pub fn compile(compiler: &str, src: &Path, spv: &Path) -> Result<(), String> {
    let output = Command::new(compiler)
        .args(["-V", "--target-env", target_env(src), "-o"])
        .arg(spv)
        .arg(src)
        .output()
        .map_err(|e| format!("cannot run {compiler}: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "shader {} failed to compile:\n{}{}",
            src.display(),
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    if src.extension().is_some_and(|e| e == "comp") {
        strip_workgroup_size_builtin(spv)?;
    }
    Ok(())
}

/// Removes the `BuiltIn WorkgroupSize` decoration glslang puts on its `gl_WorkGroupSize`
/// constant. The `LocalSize` execution mode states the size already and the constant keeps its
/// value; the best-practices layer flags the built-in as deprecated (SPIR-V 1.6 deprecates it)
/// whatever the module's version.
pub fn strip_workgroup_size_builtin(spv: &Path) -> Result<(), String> {
    const MAGIC: u32 = 0x0723_0203;
    const OP_DECORATE: u32 = 71;
    const DECORATION_BUILT_IN: u32 = 11;
    const BUILT_IN_WORKGROUP_SIZE: u32 = 25;
    let bytes = std::fs::read(spv).map_err(|e| format!("{}: {e}", spv.display()))?;
    let words: Vec<u32> = bytes.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    if bytes.len() % 4 != 0 || words.len() < 5 || words[0] != MAGIC {
        return Err(format!("{}: not little-endian SPIR-V", spv.display()));
    }
    let mut kept = words[..5].to_vec();
    let mut i = 5;
    while i < words.len() {
        let count = (words[i] >> 16) as usize;
        let Some(inst) = words.get(i..i + count).filter(|_| count > 0) else {
            return Err(format!("{}: malformed instruction at word {i}", spv.display()));
        };
        let decorates_workgroup_size =
            inst[0] & 0xffff == OP_DECORATE && count == 4 && inst[2] == DECORATION_BUILT_IN && inst[3] == BUILT_IN_WORKGROUP_SIZE;
        if !decorates_workgroup_size {
            kept.extend_from_slice(inst);
        }
        i += count;
    }
    let out: Vec<u8> = kept.iter().flat_map(|w| w.to_le_bytes()).collect();
    std::fs::write(spv, out).map_err(|e| format!("{}: {e}", spv.display()))
}

/// spirv-val, when installed (false: not installed).
pub fn validate(spv: &Path) -> Result<bool, String> {
    let Ok(output) = Command::new("spirv-val").args(["--target-env", "vulkan1.3"]).arg(spv).output() else {
        return Ok(false);
    };
    if !output.status.success() {
        return Err(format!("{} failed spirv-val:\n{}", spv.display(), String::from_utf8_lossy(&output.stderr)));
    }
    Ok(true)
}

/// FNV-1a 64 of a shader and every shared include (any include change restales every shader:
/// simpler than following #include lines, and includes change rarely).
pub fn source_hash(src: &Path, include_dir: &Path) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    let mut eat = |bytes: &[u8]| {
        for b in bytes {
            h ^= *b as u64;
            h = h.wrapping_mul(0x100000001b3);
        }
    };
    eat(&std::fs::read(src).unwrap_or_default());
    let mut includes: Vec<PathBuf> =
        std::fs::read_dir(include_dir).map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect()).unwrap_or_default();
    includes.sort();
    for inc in includes {
        eat(inc.file_name().and_then(|f| f.to_str()).unwrap_or_default().as_bytes());
        // Line endings normalised, so a checkout with CRLF hashes the same.
        eat(&std::fs::read(&inc).unwrap_or_default().into_iter().filter(|b| *b != b'\r').collect::<Vec<_>>());
    }
    h
}
