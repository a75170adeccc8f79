#!/usr/bin/env bash
# Formatting and lints, as CI runs them before the tests: `cargo fmt --check` (settings in
# rustfmt.toml), clippy on every crate and target with warnings as errors, rustdoc.
set -euo pipefail
cd "$(dirname "$0")/.."
for component in rustfmt clippy; do
  if ! cargo "${component/rustfmt/fmt}" --version >/dev/null 2>&1; then
    echo "[lint] installing the $component component" >&2
    rustup component add "$component"
  fi
done
cargo fmt --all --check
cargo clippy --workspace --all-targets --locked -- -D warnings
# The SDK alone, without the features the workspace's other crates turn on (bench-floor).
cargo clippy -p hybrid-rt --lib --locked -- -D warnings
# The API reference: every public item documented (the crate denies missing_docs), no broken
# intra-doc links.
RUSTDOCFLAGS="-D warnings" cargo doc -p hybrid-rt -p hybrid-rt-c -p hybrid-rt-wgpu --no-deps --locked
# Test-only SDK features stay out of the sample's build: Cargo's feature unification would
# otherwise switch `bench-floor` or `fault-injection` on in an application's build of it.
features=$(cargo tree --locked -e features -p hybrid-rt-samples --edges normal -i hybrid-rt)
if grep -Eq 'bench-floor|fault-injection' <<<"$features"; then
  echo "lint: the sample's build turns on a test-only SDK feature:" >&2
  echo "$features" >&2
  exit 1
fi
echo "lint: fmt, clippy and rustdoc clean; the sample builds the SDK with its default features"
