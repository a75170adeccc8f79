#!/usr/bin/env bash
# Checks the crates users build (the SDK, its C ABI and the test kit) with the oldest Rust the
# workspace declares (`rust-version` in Cargo.toml), installing that toolchain with rustup
# (minimal profile, about 60 MB) when it is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
msrv=$(sed -n 's/^rust-version = "\(.*\)"/\1/p' Cargo.toml | head -1)
[ -n "$msrv" ] || { echo "msrv: no rust-version in Cargo.toml" >&2; exit 1; }
if ! command -v rustup >/dev/null 2>&1; then
  echo "msrv: rustup is needed to install Rust $msrv" >&2
  exit 1
fi
if ! rustup run "$msrv" rustc --version >/dev/null 2>&1; then
  rustup toolchain install "$msrv" --profile minimal
fi
cargo "+$msrv" check --locked -p hybrid-rt -p hybrid-rt-c -p hybrid-rt-testkit
echo "msrv: builds with Rust $msrv"
