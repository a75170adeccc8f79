//! The shape the code keeps, so it stays easy to read: no function in the SDK, the samples, the
//! bench or the host crate over 150 lines, no C ABI file over 600, and no two modules of the
//! sample crate that import each other. Reads source files only (no GPU).
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const MAX_FUNCTION_LINES: usize = 150;
const MAX_C_ABI_FILE_LINES: usize = 600;

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("the test kit sits in the workspace").to_path_buf()
}

fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else { continue };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                if p.file_name().is_some_and(|n| n != "target") {
                    stack.push(p);
                }
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Functions of rustfmt-formatted source longer than `max` lines: (first line, name, lines).
/// A function's body ends at the first line that is its own indentation followed by `}`.
fn long_functions(source: &str, max: usize) -> Vec<(usize, String, usize)> {
    let lines: Vec<&str> = source.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let trimmed = line.trim_start();
        let indent = &line[..line.len() - trimmed.len()];
        let Some(at) = trimmed.find("fn ") else { continue };
        // Only a declaration: qualifiers before `fn`, then a name and a parameter list.
        let before = &trimmed[..at];
        let qualifiers = before
            .split_whitespace()
            .all(|w| w.starts_with("pub") || matches!(w, "const" | "async" | "unsafe" | "extern" | "\"C\"" | "default"));
        let name: String = trimmed[at + 3..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        if !qualifiers || name.is_empty() || trimmed.starts_with("//") {
            continue;
        }
        // The line that opens the body (or ends a body-less declaration).
        let Some(open) = (i..lines.len()).find(|&j| {
            let l = lines[j].trim_end();
            l.ends_with('{') || l.ends_with(';')
        }) else {
            continue;
        };
        let opening = lines[open].trim_end();
        if opening.ends_with(';') || opening.trim_end_matches('{').contains('}') {
            continue;
        }
        let closing = format!("{indent}}}");
        if let Some(end) = (open + 1..lines.len()).find(|&j| lines[j].trim_end() == closing) {
            let n = end - i + 1;
            if n > max {
                out.push((i + 1, name, n));
            }
        }
    }
    out
}

#[test]
fn no_function_is_over_150_lines() {
    let root = workspace();
    let mut long = Vec::new();
    for dir in ["sdk", "samples", "bench", "host"] {
        for file in rust_files(&root.join(dir)) {
            let source = std::fs::read_to_string(&file).unwrap();
            for (line, name, n) in long_functions(&source, MAX_FUNCTION_LINES) {
                long.push(format!("{}:{line} {name} ({n} lines)", file.strip_prefix(&root).unwrap().display()));
            }
        }
    }
    assert!(long.is_empty(), "functions over {MAX_FUNCTION_LINES} lines — split them:\n{}", long.join("\n"));
}

#[test]
fn no_c_abi_file_is_over_600_lines() {
    let root = workspace();
    let mut big = Vec::new();
    for file in rust_files(&root.join("sdk-c-api")) {
        let n = std::fs::read_to_string(&file).unwrap().lines().count();
        if n > MAX_C_ABI_FILE_LINES {
            big.push(format!("{} ({n} lines)", file.strip_prefix(&root).unwrap().display()));
        }
    }
    assert!(big.is_empty(), "C ABI files over {MAX_C_ABI_FILE_LINES} lines — split them by API area:\n{}", big.join("\n"));
}

/// The top-level module a file of `src` belongs to (`renderer/mod.rs` → `renderer`).
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).ok()?;
    let first = rel.components().next()?.as_os_str().to_str()?;
    let name = first.trim_end_matches(".rs");
    (!matches!(name, "lib" | "main" | "bin")).then(|| name.to_owned())
}

/// The first-level names of each `crate::{...}` group (`use crate::{raster, scene::Scene}`).
fn crate_use_groups(source: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (at, _) in source.match_indices("crate::{") {
        let mut depth = 0;
        let mut names = String::new();
        for c in source[at + "crate::{".len()..].chars() {
            match c {
                '{' => depth += 1,
                '}' if depth == 0 => break,
                '}' => depth -= 1,
                _ if depth == 0 => names.push(c),
                _ => {}
            }
        }
        // Keep only each item's first segment: `scene::Scene` names the module `scene`.
        out.push(names.split(',').map(|item| item.trim().split("::").next().unwrap_or("")).collect::<Vec<_>>().join(","));
    }
    out
}

#[test]
fn no_two_sample_modules_import_each_other() {
    let src = workspace().join("samples/src");
    let files = rust_files(&src);
    let modules: BTreeSet<String> = files.iter().filter_map(|f| module_of(&src, f)).collect();
    let mut uses: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for file in &files {
        let Some(from) = module_of(&src, file) else { continue };
        let source = std::fs::read_to_string(file).unwrap();
        let groups = crate_use_groups(&source);
        for to in &modules {
            let named = source.contains(&format!("crate::{to}::"))
                || groups.iter().any(|g| g.split(|c: char| !(c.is_alphanumeric() || c == '_')).any(|w| w == to));
            if *to != from && named {
                uses.entry(from.clone()).or_default().insert(to.clone());
            }
        }
    }
    let mut circles = Vec::new();
    for (a, targets) in &uses {
        for b in targets {
            if a < b && uses.get(b).is_some_and(|t| t.contains(a)) {
                circles.push(format!("{a} <-> {b}"));
            }
        }
    }
    assert!(circles.is_empty(), "sample modules that import each other:\n{}", circles.join("\n"));
}

#[test]
fn the_length_check_finds_long_functions_and_nothing_else() {
    let body: String = (0..160).map(|i| format!("    let x{i} = {i};\n")).collect();
    let source = format!(
        "pub(crate) unsafe fn long() {{\n{body}}}\n\nfn short() {{\n    1\n}}\n\nfn decl();\n    fn one_line() {{ 1 }}\n"
    );
    assert_eq!(long_functions(&source, 150), vec![(1, "long".to_owned(), 162)]);
    assert!(long_functions("impl X {\n    fn inner() {\n        a();\n    }\n}\n", 2).iter().all(|(_, n, _)| n == "inner"));
}
