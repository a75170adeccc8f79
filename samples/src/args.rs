//! Tiny `--key value` parsing (the binaries take a handful of numeric options).
use std::collections::HashMap;

pub struct Args(HashMap<String, String>);

impl Args {
    /// Parses `--key value` and `--flag` pairs; prints `usage` and exits on `--help`.
    pub fn parse(usage: &str) -> Args {
        let mut map = HashMap::new();
        let mut it = std::env::args().skip(1).peekable();
        while let Some(a) = it.next() {
            if a == "--help" || a == "-h" {
                println!("{usage}");
                std::process::exit(0);
            }
            let Some(key) = a.strip_prefix("--") else {
                eprintln!("unexpected argument {a}\n{usage}");
                std::process::exit(2);
            };
            let value = match it.peek() {
                Some(v) if !v.starts_with("--") => it.next().unwrap(),
                _ => "true".to_string(),
            };
            map.insert(key.to_string(), value);
        }
        Args(map)
    }

    pub fn get<T: std::str::FromStr>(&self, key: &str, default: T) -> T {
        match self.0.get(key) {
            None => default,
            Some(v) => v.parse().unwrap_or_else(|_| {
                eprintln!("--{key}: cannot parse {v:?}");
                std::process::exit(2)
            }),
        }
    }

    pub fn list(&self, key: &str, default: &[u32]) -> Vec<u32> {
        match self.0.get(key) {
            None => default.to_vec(),
            Some(v) => v.split(',').map(|s| s.trim().parse().expect("comma-separated numbers")).collect(),
        }
    }

    pub fn string(&self, key: &str, default: &str) -> String {
        self.0.get(key).cloned().unwrap_or_else(|| default.to_string())
    }
}
