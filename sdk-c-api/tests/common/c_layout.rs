//! The byte layout of the C ABI's structs, read from the generated header: every scalar leaf
//! (nested structs and arrays flattened) with its offset and kind, so a test can overwrite any
//! field of any struct with raw bytes. The layout is checked against Rust's `size_of` of the
//! same struct, so a header this parser misreads fails loudly instead of fuzzing the wrong bytes.
use std::collections::HashMap;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// 4 bytes: uint32_t, int32_t, float, Vulkan enums.
    Word,
    /// 8 bytes: uint64_t, double, Vulkan and SDK handles.
    Wide,
    Bool,
    Byte,
    /// A Vulkan object handle: only ever set to VK_NULL_HANDLE. Any other value that is not
    /// a live object of the device breaks Vulkan's rules, which the SDK cannot check (it hands
    /// the handle to the driver, as every Vulkan library does).
    VulkanHandle,
    /// A pointer: left alone (a C caller that passes a wild pointer breaks C's rules first).
    Pointer,
}

#[derive(Clone, Debug)]
pub struct Leaf {
    pub path: String,
    pub offset: usize,
    pub kind: Kind,
    /// A pointer, or the element count that goes with a pointer in the same struct: changing
    /// it would make the SDK read past the caller's array.
    pub protected: bool,
}

struct Field {
    ty: String,
    name: String,
    len: usize,
    pointer: bool,
}

pub struct Header {
    structs: HashMap<String, Vec<Field>>,
}

const WORDS: &[&str] =
    &["uint32_t", "int32_t", "float", "VkFormat", "VkImageLayout", "HrtTaskKind", "HrtBuildHint", "HrtHitIndirect"];
const VULKAN_HANDLES: &[&str] = &["VkBuffer", "VkImage", "VkImageView", "VkInstance", "VkPhysicalDevice", "VkDevice"];
const WIDES: &[&str] = &[
    "uint64_t",
    "double",
    "HrtGeometryHandle",
    "HrtInstanceHandle",
    "HrtDenoisingContextHandle",
    "HrtManyLightsContextHandle",
    "HrtTicket",
];

impl Header {
    pub fn parse(text: &str) -> Header {
        let mut structs = HashMap::new();
        let mut current: Option<(String, Vec<Field>)> = None;
        let mut in_comment = false;
        let mut defines = HashMap::new();
        for line in text.lines() {
            let t = line.trim();
            if let Some(rest) = t.strip_prefix("#define ") {
                if let Some((name, value)) = rest.split_once(' ') {
                    if let Ok(v) = value.trim().parse::<usize>() {
                        defines.insert(name.to_string(), v);
                    }
                }
                continue;
            }
            if t.starts_with("/*") {
                in_comment = !t.contains("*/");
                continue;
            }
            if in_comment {
                in_comment = !t.contains("*/");
                continue;
            }
            if let Some(name) = t.strip_prefix("typedef struct ").and_then(|r| r.strip_suffix(" {")) {
                current = Some((name.to_string(), Vec::new()));
                continue;
            }
            if t.starts_with('}') {
                if let Some((name, fields)) = current.take() {
                    structs.insert(name, fields);
                }
                continue;
            }
            let Some((_, fields)) = current.as_mut() else { continue };
            let Some(decl) = t.strip_suffix(';') else { continue };
            let decl = decl.replace("const ", "").replace("struct ", "");
            let pointer = decl.contains('*');
            let decl = decl.replace('*', " ");
            let mut words = decl.split_whitespace();
            let ty = words.next().expect("a field type").to_string();
            let declarator = words.last().expect("a field name");
            let (name, len) = match declarator.split_once('[') {
                Some((n, rest)) => {
                    let len = rest.trim_end_matches(']');
                    let len = len.parse().ok().or_else(|| defines.get(len).copied()).expect("an array length");
                    (n.to_string(), len)
                }
                None => (declarator.to_string(), 1),
            };
            fields.push(Field { ty, name, len, pointer });
        }
        Header { structs }
    }

    /// Size and alignment of a field type.
    fn size_align(&self, ty: &str, pointer: bool) -> (usize, usize) {
        if pointer || ty.starts_with("PFN_") {
            (8, 8)
        } else if WORDS.contains(&ty) {
            (4, 4)
        } else if WIDES.contains(&ty) || VULKAN_HANDLES.contains(&ty) {
            (8, 8)
        } else if ty == "bool" || ty == "char" {
            (1, 1)
        } else if self.structs.contains_key(ty) {
            let (leaves_size, align) = self.layout(ty, 0, "", &mut Vec::new());
            (leaves_size, align)
        } else {
            panic!("the header's type {ty} is not known to the layout reader");
        }
    }

    /// Appends the leaves of struct `name` placed at `base`; returns its size and alignment.
    fn layout(&self, name: &str, base: usize, prefix: &str, out: &mut Vec<Leaf>) -> (usize, usize) {
        let fields = &self.structs[name];
        let has_pointer = fields.iter().any(|f| f.pointer);
        let (mut offset, mut align) = (0usize, 1usize);
        for f in fields {
            let (size, a) = self.size_align(&f.ty, f.pointer);
            offset = offset.next_multiple_of(a);
            align = align.max(a);
            for i in 0..f.len {
                let at = base + offset + i * size;
                let path = if f.len > 1 { format!("{prefix}{}[{i}]", f.name) } else { format!("{prefix}{}", f.name) };
                let kind = if f.pointer || f.ty.starts_with("PFN_") {
                    Some(Kind::Pointer)
                } else if WORDS.contains(&f.ty.as_str()) {
                    Some(Kind::Word)
                } else if WIDES.contains(&f.ty.as_str()) {
                    Some(Kind::Wide)
                } else if VULKAN_HANDLES.contains(&f.ty.as_str()) {
                    Some(Kind::VulkanHandle)
                } else if f.ty == "bool" {
                    Some(Kind::Bool)
                } else if f.ty == "char" {
                    Some(Kind::Byte)
                } else {
                    None
                };
                match kind {
                    Some(kind) => {
                        let protected = kind == Kind::Pointer || (has_pointer && f.name.ends_with("_count"));
                        out.push(Leaf { path, offset: at, kind, protected });
                    }
                    None => {
                        self.layout(&f.ty, at, &format!("{path}."), out);
                    }
                }
            }
            offset += size * f.len;
        }
        (offset.next_multiple_of(align), align)
    }

    /// The leaves of struct `name`, checked against the Rust struct's size.
    pub fn leaves(&self, name: &str, rust_size: usize) -> Vec<Leaf> {
        let mut out = Vec::new();
        let (size, _) = self.layout(name, 0, "", &mut out);
        assert_eq!(size, rust_size, "{name}: the header's layout and Rust's differ");
        out
    }
}

/// `good` with each `(leaf, value)` written over it: words take the low 32 bits, bools the
/// lowest bit, wide fields all 64; Vulkan handles become null. Protected leaves must not be among them.
pub fn overwrite<T: Copy>(good: &T, leaves: &[Leaf], edits: &[(usize, u64)]) -> T {
    let mut t = *good;
    // SAFETY: T is a plain C struct; every edit stays inside it (offsets from its layout,
    // checked against size_of) and writes a valid value of its field's type (bools 0 or 1;
    // pointers are never written).
    let bytes = unsafe { std::slice::from_raw_parts_mut(&mut t as *mut T as *mut u8, std::mem::size_of::<T>()) };
    for &(i, value) in edits {
        let leaf = &leaves[i];
        assert!(!leaf.protected, "{} is protected", leaf.path);
        let at = leaf.offset;
        match leaf.kind {
            Kind::Word => bytes[at..at + 4].copy_from_slice(&(value as u32).to_ne_bytes()),
            Kind::Wide => bytes[at..at + 8].copy_from_slice(&value.to_ne_bytes()),
            Kind::VulkanHandle => bytes[at..at + 8].fill(0),
            Kind::Bool => bytes[at] = (value & 1) as u8,
            Kind::Byte => bytes[at] = value as u8,
            Kind::Pointer => unreachable!(),
        }
    }
    t
}
