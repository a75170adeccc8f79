#!/usr/bin/env bash
# README command 1: installs what is missing (scripts/setup.sh), builds the sample in release
# mode and renders the built-in room into out/: ray-traced AO (EXR + PNG), the lit frame it
# injects, and one PNG per debug visualisation of the direct-lighting cache, printing the
# per-task GPU times. Extra arguments go to the sample (see `--help`).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo run --release --locked -p hybrid-rt-samples --bin sample -- --out out "$@"
echo "images in $(pwd)/out/: ao.png and ao.exr (AO), lit.png, debug_*.png (cache and debug views), *_noisy_vs_denoised.png"
