//! The documentation speaks to users: no paths into the maintainers' notes, no issue numbers,
//! no "breaking for main", and no link to a module or a file that does not exist.
//!
//! Scans README.md, docs/*.md (the contributors' design notes too),
//! CHANGELOG.md, and every `//!` and `///` comment in sdk/src, wgpu-bridge/src, tests/src and
//! bevy/src.
//! Reads files only: no GPU.
use std::path::{Path, PathBuf};

/// The workspace's crates, by the name code uses, and their sources: where a path such as
/// `hybrid_rt::types::denoise` or `crate::passes::inject` is looked up.
const CRATES: &[(&str, &str)] = &[
    ("hybrid_rt", "sdk/src"),
    ("hybrid_rt_wgpu", "wgpu-bridge/src"),
    ("hybrid_rt_testkit", "tests/src"),
    ("hybrid_rt_host", "host/src"),
    ("hybrid_rt_samples", "samples/src"),
    ("hybrid_rt_bench", "bench/src"),
    ("hybrid_rt_c", "sdk-c-api/src"),
    ("hybrid_rt_bevy", "bevy/src"),
];

/// First path segments that are not the workspace's: other crates and primitive types.
const EXTERNAL: &[&str] = &[
    "std",
    "core",
    "alloc",
    "ash",
    "vk",
    "khr",
    "ext",
    "glam",
    "wgpu",
    "wgpu_hal",
    "bevy",
    "hal",
    "wgt",
    "bytemuck",
    "log",
    "png",
    "exr",
    "half",
    "serde",
    "serde_json",
    "clap",
    "indicatif",
    "gpu_allocator",
    "parking_lot",
    "thiserror",
    "bitflags",
    "winit",
    "gltf",
    "u8",
    "u16",
    "u32",
    "u64",
    "u128",
    "usize",
    "i8",
    "i16",
    "i32",
    "i64",
    "i128",
    "isize",
    "f32",
    "f64",
    "bool",
    "char",
    "str",
];

/// Paths that are not Rust: (file, path, what it is).
const NOT_RUST: &[(&str, &str, &str)] = &[
    ("docs/c-api.md", "hybrid_rt::hybrid_rt", "a CMake target"),
    ("docs/c-api.md", "hybrid_rt::hybrid_rt_static", "a CMake target"),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

/// One line of documentation: the file (relative to the root), its line number, the text, and
/// the crate a Rust file belongs to.
struct Line {
    file: String,
    number: usize,
    text: String,
    home: Option<&'static str>,
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<_> = entries.map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

fn relative(p: &Path) -> String {
    p.strip_prefix(root()).unwrap().to_string_lossy().replace('\\', "/")
}

/// Every line of the scanned markdown files and every doc-comment line of the scanned crates.
fn documentation() -> Vec<Line> {
    let root = root();
    let mut markdown = vec![root.join("README.md"), root.join("CHANGELOG.md")];
    let mut guides: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    guides.sort();
    markdown.extend(guides);
    let mut lines = Vec::new();
    for p in markdown {
        let text = std::fs::read_to_string(&p).unwrap();
        for (i, l) in text.lines().enumerate() {
            lines.push(Line { file: relative(&p), number: i + 1, text: l.to_string(), home: None });
        }
    }
    for (name, src) in [
        ("hybrid_rt", "sdk/src"),
        ("hybrid_rt_wgpu", "wgpu-bridge/src"),
        ("hybrid_rt_testkit", "tests/src"),
        ("hybrid_rt_bevy", "bevy/src"),
    ] {
        let mut files = Vec::new();
        rust_files(&root.join(src), &mut files);
        assert!(!files.is_empty(), "no Rust files in {src}");
        for p in files {
            let text = std::fs::read_to_string(&p).unwrap();
            for (i, l) in text.lines().enumerate() {
                let t = l.trim_start();
                if let Some(doc) = t.strip_prefix("//!").or_else(|| t.strip_prefix("///")) {
                    lines.push(Line { file: relative(&p), number: i + 1, text: doc.to_string(), home: Some(name) });
                }
            }
        }
    }
    lines
}

/// `issue 12`, `issue #12`, `issues #3`, `issue#4`, any case.
fn names_an_issue(text: &str) -> bool {
    let lower = text.to_lowercase();
    let b = lower.as_bytes();
    let mut from = 0;
    while let Some(at) = lower[from..].find("issue") {
        let mut i = from + at + "issue".len();
        if b.get(i) == Some(&b's') {
            i += 1;
        }
        let spaced = b.get(i) == Some(&b' ');
        if spaced {
            i += 1;
        }
        let hashed = b.get(i) == Some(&b'#');
        if hashed {
            i += 1;
        }
        if (spaced || hashed) && b.get(i).is_some_and(u8::is_ascii_digit) {
            return true;
        }
        from += at + 1;
    }
    false
}

/// The `a::b::c` paths of a line whose first segment starts with a lower-case letter or `_`
/// (module paths; `Type::item` is left to rustdoc).
fn module_paths(text: &str) -> Vec<String> {
    let is_ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let chars: Vec<char> = text.chars().collect();
    let mut paths = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let starts =
            (chars[i].is_ascii_alphabetic() || chars[i] == '_') && (i == 0 || !(is_ident(chars[i - 1]) || chars[i - 1] == ':'));
        if !starts {
            i += 1;
            continue;
        }
        let mut segments = Vec::new();
        let mut j = i;
        loop {
            let s = j;
            while j < chars.len() && is_ident(chars[j]) {
                j += 1;
            }
            segments.push(chars[s..j].iter().collect::<String>());
            let more = j + 2 < chars.len()
                && chars[j] == ':'
                && chars[j + 1] == ':'
                && (chars[j + 2].is_ascii_alphabetic() || chars[j + 2] == '_');
            if !more {
                break;
            }
            j += 2;
        }
        if segments.len() > 1 && segments[0].starts_with(|c: char| c.is_ascii_lowercase() || c == '_') {
            paths.push(segments.join("::"));
        }
        i = j.max(i + 1);
    }
    paths
}

/// The sources of a crate, read once.
struct Sources {
    name: &'static str,
    src: PathBuf,
    text: String,
}

/// Whether a crate declares an item called `name` (or re-exports one), in any of its files.
fn declares(sources: &Sources, name: &str) -> bool {
    let word = |line: &str, at: usize| {
        let before = line[..at].chars().next_back();
        let after = line[at + name.len()..].chars().next();
        !before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_')
            && !after.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    let keywords = ["fn ", "struct ", "enum ", "trait ", "type ", "const ", "static ", "mod ", "macro_rules! ", "union "];
    sources.text.lines().any(|line| {
        let t = line.trim_start();
        let reexport = t.starts_with("pub use ") || t.starts_with("pub(crate) use ");
        line.match_indices(name).any(|(at, _)| word(line, at) && (reexport || keywords.iter().any(|k| line[..at].ends_with(k))))
    })
}

/// Whether `path` names a module (and then, optionally, an item) that exists. `home` is the
/// crate whose comment holds it (None for markdown).
fn resolves(path: &str, home: Option<&str>, crates: &[Sources]) -> bool {
    let segments: Vec<&str> = path.split("::").collect();
    let by_name = |n: &str| crates.iter().find(|c| c.name == n);
    let is_module = |c: &Sources, seg: &str| c.src.join(format!("{seg}.rs")).exists() || c.src.join(seg).join("mod.rs").exists();
    let (krate, rest) = match segments[0] {
        "self" | "super" => return true,
        "crate" => (by_name(home.unwrap_or("hybrid_rt")).unwrap(), &segments[1..]),
        first => match by_name(first) {
            Some(c) => (c, &segments[1..]),
            // A module path without its crate: the comment's own crate's, or the SDK's.
            None => {
                let candidates = [home.and_then(by_name), by_name("hybrid_rt")];
                match candidates.into_iter().flatten().find(|c| is_module(c, first)) {
                    Some(c) => (c, &segments[..]),
                    None => return false,
                }
            }
        },
    };
    let mut dir = krate.src.clone();
    for seg in rest {
        if dir.join(format!("{seg}.rs")).exists() || dir.join(seg).join("mod.rs").exists() {
            dir = dir.join(seg);
            continue;
        }
        // Not a module file: an item of the module (or one the crate re-exports).
        return declares(krate, seg);
    }
    true
}

/// The targets of `[text](target)` and `src="target"` in a markdown line that are files of
/// the repository (not URLs, anchors or Rust paths).
fn file_links(text: &str) -> Vec<String> {
    let mut targets = Vec::new();
    for (open, close) in [("](", ')'), ("src=\"", '"')] {
        let mut rest = text;
        while let Some(at) = rest.find(open) {
            rest = &rest[at + open.len()..];
            let Some(end) = rest.find(close) else { break };
            let target = rest[..end].split('#').next().unwrap().trim();
            let external = ["http://", "https://", "mailto:"].iter().any(|s| target.starts_with(s));
            if !target.is_empty() && !external && !target.contains("::") && !target.contains(' ') {
                targets.push(target.to_string());
            }
            rest = &rest[end..];
        }
    }
    targets
}

#[test]
fn the_documentation_names_no_internal_paths_issues_or_missing_modules() {
    let root = root();
    let crates: Vec<Sources> = CRATES
        .iter()
        .map(|&(name, src)| {
            let mut files = Vec::new();
            rust_files(&root.join(src), &mut files);
            let text = files.iter().map(|p| std::fs::read_to_string(p).unwrap()).collect::<Vec<_>>().join("\n");
            Sources { name, src: root.join(src), text }
        })
        .collect();
    let lines = documentation();
    assert!(lines.len() > 1000, "only {} lines of documentation found", lines.len());
    let mut problems = Vec::new();
    for line in &lines {
        let mut problem = |what: String| problems.push(format!("{}:{}: {what}: {}", line.file, line.number, line.text.trim()));
        if line.text.contains("shared/") {
            problem("a path into the maintainers' notes (shared/)".into());
        }
        if names_an_issue(&line.text) {
            problem("an issue number".into());
        }
        if line.text.to_lowercase().contains("breaking for main") {
            problem("\"breaking for main\"".into());
        }
        for path in module_paths(&line.text) {
            let first = path.split("::").next().unwrap();
            let not_rust = NOT_RUST.iter().any(|&(f, p, _)| f == line.file && p == path);
            if !EXTERNAL.contains(&first) && !not_rust && !resolves(&path, line.home, &crates) {
                problem(format!("`{path}` names a module or item that does not exist"));
            }
        }
        if line.home.is_none() {
            let dir = root.join(&line.file).parent().unwrap().to_path_buf();
            for target in file_links(&line.text) {
                if !dir.join(&target).exists() {
                    problem(format!("the link to {target} leads nowhere"));
                }
            }
        }
    }
    assert!(problems.is_empty(), "{} documentation problems:\n{}", problems.len(), problems.join("\n"));
}

/// The checks themselves, on made-up lines, so a scan that finds nothing is not a scan that
/// cannot find anything.
#[test]
fn the_checks_catch_what_they_are_for() {
    assert!(names_an_issue("(issue 12)") && names_an_issue("Issues #3") && names_an_issue("see issue#4"));
    assert!(!names_an_issue("issued tickets") && !names_an_issue("the issue asks") && !names_an_issue("an issue: 5"));
    assert_eq!(module_paths("see `api::denoising` and `Error::Internal`, glam's vk::Format"), ["api::denoising", "vk::Format"]);
    assert_eq!(module_paths("[`x`](crate::types::denoise) a::b::{c, d}"), ["crate::types::denoise", "a::b"]);
    let root = root();
    let sdk = [Sources { name: "hybrid_rt", src: root.join("sdk/src"), text: "pub struct DeviceFeatures;\npub use ash;".into() }];
    assert!(resolves("crate::types::denoise", Some("hybrid_rt"), &sdk));
    assert!(resolves("hybrid_rt::DeviceFeatures::chain", None, &sdk));
    assert!(resolves("hybrid_rt::ash::vk", None, &sdk));
    assert!(resolves("types::denoise", None, &sdk));
    assert!(!resolves("api::denoising", Some("hybrid_rt"), &sdk));
    assert!(!resolves("hybrid_rt::api::denoising", None, &sdk));
    assert!(!resolves("crate::context::render", Some("hybrid_rt"), &sdk));
    assert!(!resolves("hybrid_rt::NoSuchThing", None, &sdk));
    assert_eq!(file_links("[a](docs/x.md#y) ![b](https://e.org) <img src=\"i.png\"> [c](#z)"), ["docs/x.md", "i.png"]);
}
