#!/usr/bin/env bash
# README command 2: installs what is missing (scripts/setup.sh), then runs every test of the
# workspace on the machine's Vulkan ray-tracing device — Mesa's lavapipe on a machine without
# a GPU — with the Khronos validation layer on (a validation error fails the test).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export RUST_BACKTRACE="${RUST_BACKTRACE:-1}"
start=$(date +%s)
cargo test --workspace --locked "$@"
echo "test suite finished in $(( $(date +%s) - start )) s"
