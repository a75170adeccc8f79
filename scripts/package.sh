#!/usr/bin/env bash
# Packages the hybrid-rt crate as crates.io would, then builds and tests the package from its
# own folder with no shader compiler on PATH: the crate must build from its shipped SPIR-V.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
cargo package -p hybrid-rt --locked --allow-dirty --no-verify
version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -1)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
tar -xzf "target/package/hybrid-rt-$version.crate" -C "$work"
# A PATH with Rust and the C toolchain's driver only: no glslangValidator, no spirv-val.
mkdir -p "$work/bin"
for tool in cargo rustc rustup cc gcc ld as ar; do
  p=$(command -v "$tool" || true)
  [ -n "$p" ] && ln -s "$p" "$work/bin/$tool"
done
if PATH="$work/bin" command -v glslangValidator >/dev/null 2>&1; then echo "glslangValidator still on PATH" >&2; exit 1; fi
cd "$work/hybrid-rt-$version"
PATH="$work/bin" CARGO_TARGET_DIR="$root/target/package-check" cargo build --locked --lib
PATH="$work/bin" CARGO_TARGET_DIR="$root/target/package-check" cargo test --locked --lib
# The doctests compile from the package, and so does the example (it runs in .ci/run).
PATH="$work/bin" CARGO_TARGET_DIR="$root/target/package-check" cargo test --locked --doc
PATH="$work/bin" CARGO_TARGET_DIR="$root/target/package-check" cargo build --locked --examples
echo "package: hybrid-rt $version builds from the package, without a shader compiler"
