#!/usr/bin/env bash
# README command 1: installs what is missing (scripts/setup.sh), builds the sample in release
# mode and renders ray-traced AO of the built-in room into out/ (EXR + PNG preview), printing
# the per-task GPU times. Extra arguments go to the sample (see `--help`).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo run --release --locked -p hybrid-rt-samples --bin sample -- --out out "$@"
echo "images: $(pwd)/out/ao.png (preview) and $(pwd)/out/ao.exr (linear float)"
