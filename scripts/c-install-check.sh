#!/usr/bin/env bash
# Installs the C library into a scratch prefix (scripts/install-c.sh) and builds the C samples
# against that tree only — never against the repository — four ways: pkg-config shared and
# static, CMake shared and static. Runs each (the samples check its own results on the
# machine's ray-tracing device, under the validation layer when installed).
set -euo pipefail
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"
./scripts/install-c.sh "$prefix"
src="samples/c/tour.c samples/c/engine.c"
flags="-std=c11 -Wall -Wextra -Werror -Wno-missing-field-initializers -O1"
export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"

echo "[c-install] pkg-config $(pkg-config --modversion hybrid_rt)"
# shellcheck disable=SC2046,SC2086
cc $flags $(pkg-config --cflags hybrid_rt) $src -o "$work/pc_shared" $(pkg-config --libs hybrid_rt) -lm
# Static: the archive by name (-l would pick the .so beside it), then what it needs.
# shellcheck disable=SC2046,SC2086
cc $flags $(pkg-config --cflags hybrid_rt) $src -o "$work/pc_static" \
  $(pkg-config --static --libs hybrid_rt | sed 's/-lhybrid_rt /-l:libhybrid_rt.a /') -lm

echo "[c-install] cmake"
cmake -S samples/c -B "$work/cmake" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/cmake" >/dev/null

# The shared builds must load the installed library through its SONAME. ldd's output is
# captured before it is searched: `ldd | grep -q` under pipefail fails at random, because grep
# stops at the first match and ldd dies of SIGPIPE while still writing.
for exe in "$work/pc_shared" "$work/cmake/tour" "$work/cmake/ao"; do
  libs=$(LD_LIBRARY_PATH="$prefix/lib" ldd "$exe")
  grep -q "libhybrid_rt.so.0.* => $prefix/lib/" <<<"$libs" \
    || { echo "[c-install] $exe does not load the installed libhybrid_rt" >&2; echo "$libs" >&2; exit 1; }
done
for exe in "$work/pc_static" "$work/cmake/tour_static"; do
  libs=$(ldd "$exe")
  if grep -q libhybrid_rt <<<"$libs"; then echo "[c-install] $exe is not static" >&2; exit 1; fi
done
for exe in "$work/pc_shared" "$work/pc_static" "$work/cmake/tour" "$work/cmake/ao" "$work/cmake/tour_static"; do
  echo "[c-install] running ${exe#"$work"/}"
  LD_LIBRARY_PATH="$prefix/lib" "$exe" >"$work/log" 2>&1 || { cat "$work/log" >&2; exit 1; }
done
echo "c-install: the installed tree builds and runs the C samples via pkg-config and CMake (shared and static)"
