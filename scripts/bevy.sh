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
cargo run --locked --example bevy_ao -- --out target/bevy_ao.png --shadow-out target/bevy_sun_shadow.png --gi-out target/bevy_gi.png
# The deferred path: GI, reflections and the sun's shadow composited into the lit image.
cargo run --locked --example bevy_ao -- --out target/bevy_shiny_rt.png --gi-out target/bevy_gi_deferred.png --reflections-out target/bevy_reflections.png \
  --shadow-out target/bevy_sun_shadow_deferred.png
# The window path, under Xvfb where it is installed (scripts/setup.sh installs it).
if command -v xvfb-run >/dev/null 2>&1; then
  xvfb-run -a cargo run --locked --example bevy_ao -- --window --frames 30
fi
echo "bevy: plugin checked in $(( $(date +%s) - start )) s"
