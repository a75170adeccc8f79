//! Tiny `--key value` parsing (the binaries take a handful of numeric options).
use std::collections::HashMap;

pub struct Args {
    named: HashMap<String, String>,
    /// Arguments that are not options (the sample's glTF file).
    pub positional: Vec<String>,
}

impl Args {
    /// Parses `--key value` and `--flag` pairs; prints `usage` and exits on `--help`.
    pub fn parse(usage: &str) -> Args {
        let mut map = HashMap::new();
        let mut positional = Vec::new();
        let mut it = std::env::args().skip(1).peekable();
        while let Some(a) = it.next() {
            if a == "--help" || a == "-h" {
                println!("{usage}");
                std::process::exit(0);
            }
            let Some(key) = a.strip_prefix("--") else {
                positional.push(a);
                continue;
            };
            let value = match it.peek() {
                Some(v) if !v.starts_with("--") => it.next().unwrap(),
                _ => "true".to_string(),
            };
            map.insert(key.to_string(), value);
        }
        Args { named: map, positional }
    }

    pub fn get<T: std::str::FromStr>(&self, key: &str, default: T) -> T {
        match self.named.get(key) {
            None => default,
            Some(v) => v.parse().unwrap_or_else(|_| {
                eprintln!("--{key}: cannot parse {v:?}");
                std::process::exit(2)
            }),
        }
    }

    pub fn list(&self, key: &str, default: &[u32]) -> Vec<u32> {
        match self.named.get(key) {
            None => default.to_vec(),
            Some(v) => v.split(',').map(|s| s.trim().parse().expect("comma-separated numbers")).collect(),
        }
    }

    /// The raw value of `--key`, if given.
    pub fn named(&self, key: &str) -> Option<String> {
        self.named.get(key).cloned()
    }

    pub fn flag(&self, key: &str) -> bool {
        self.named.get(key).is_some_and(|v| v != "false")
    }

    pub fn string(&self, key: &str, default: &str) -> String {
        self.named.get(key).cloned().unwrap_or_else(|| default.to_string())
    }
}
