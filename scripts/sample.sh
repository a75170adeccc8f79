#!/usr/bin/env bash
# README command 1: installs what is missing (scripts/setup.sh), builds the sample in release
# mode and renders the built-in room headless into out/: the composite and every
# intermediate image and debug view of the last of 16 frames along a camera path, as EXR
# (linear) and PNG, printing the frame's GPU time per pass and per SDK task, and the SDK's
# memory. Extra arguments go to the sample (`--help`): a glTF file, `--window` for the
# interactive window, `--width`/`--height`, `--modes`, ...
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo run --release --locked -p hybrid-rt-samples --bin sample -- --headless --out out "$@"
echo "images in $(pwd)/out/: composite.png (the frame), one EXR + PNG per mode (direct, ao, diffuse, specular, *_noisy, debug_*, ...)"
echo "interactive: cargo run --release -p hybrid-rt-samples --bin sample -- --window [scene.gltf]"
