#!/usr/bin/env bash
# The Bevy plugin (bevy/: its own workspace, on the Rust toolchain Bevy needs, named in
# bevy/rust-toolchain.toml): formatting, clippy, its tests on the machine's Vulkan device
# (lavapipe without a GPU) with the validation layer, and the headless example.
set -euo pipefail
cd "$(dirname "$0")/../bevy"
toolchain=$(sed -n 's/^channel = "\(.*\)"/\1/p' rust-toolchain.toml)
if ! rustup run "$toolchain" cargo clippy --version >/dev/null 2>&1; then
  echo "[bevy] installing Rust $toolchain (Bevy's minimum)" >&2
  rustup toolchain install "$toolchain" --profile minimal --component rustfmt,clippy
fi
start=$(date +%s)
cargo fmt --check
cargo clippy --all-targets --locked -- -D warnings
cargo test --locked
cargo run --locked --example bevy_ao -- --out target/bevy_ao.png
echo "bevy: plugin checked in $(( $(date +%s) - start )) s"
