#!/usr/bin/env bash
# Builds the C library in release mode and installs it as a C library is installed:
#
#   PREFIX/include/hybrid_rt.h
#   PREFIX/lib/libhybrid_rt.so.X.Y.Z        (SONAME libhybrid_rt.so.0.Y before 1.0, then .so.X)
#   PREFIX/lib/libhybrid_rt.so.<abi> -> libhybrid_rt.so.X.Y.Z
#   PREFIX/lib/libhybrid_rt.so       -> libhybrid_rt.so.<abi>   (for -lhybrid_rt)
#   PREFIX/lib/libhybrid_rt.a
#   PREFIX/lib/pkgconfig/hybrid_rt.pc        (pkg-config hybrid_rt; --static for the .a)
#   PREFIX/lib/cmake/hybrid_rt/              (find_package(hybrid_rt): hybrid_rt::hybrid_rt,
#                                             hybrid_rt::hybrid_rt_static)
#   PREFIX/share/doc/hybrid_rt/              (licences)
#
# Usage: scripts/install-c.sh PREFIX   (e.g. /usr/local, or a staging folder for a package)
set -euo pipefail
cd "$(dirname "$0")/.."
prefix=${1:?usage: scripts/install-c.sh PREFIX}
mkdir -p "$prefix"
prefix=$(cd "$prefix" && pwd)
version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -1)
major=${version%%.*}
rest=${version#*.}
minor=${rest%%.*}
if [ "$major" = 0 ]; then abi="0.$minor"; else abi="$major"; fi

# The SONAME (see sdk-c-api/build.rs) only for the installed library.
HRT_C_SONAME=1 cargo build --release --locked -p hybrid-rt-c --lib
target=${CARGO_TARGET_DIR:-target}/release

install -d "$prefix/include" "$prefix/lib/pkgconfig" "$prefix/lib/cmake/hybrid_rt" "$prefix/share/doc/hybrid_rt"
install -m 644 sdk-c-api/include/hybrid_rt.h "$prefix/include/"
install -m 755 "$target/libhybrid_rt_c.so" "$prefix/lib/libhybrid_rt.so.$version"
ln -sf "libhybrid_rt.so.$version" "$prefix/lib/libhybrid_rt.so.$abi"
ln -sf "libhybrid_rt.so.$abi" "$prefix/lib/libhybrid_rt.so"
install -m 644 "$target/libhybrid_rt_c.a" "$prefix/lib/libhybrid_rt.a"
install -m 644 LICENSE-MIT LICENSE-APACHE "$prefix/share/doc/hybrid_rt/"

# The static library needs what Rust's standard library links (rustc --print native-static-libs).
static_libs="-lgcc_s -lutil -lrt -lpthread -lm -ldl -lc"
sed -e "s|@PREFIX@|$prefix|g" -e "s|@VERSION@|$version|g" -e "s|@STATIC_LIBS@|$static_libs|g" \
  sdk-c-api/install/hybrid_rt.pc.in > "$prefix/lib/pkgconfig/hybrid_rt.pc"
sed -e "s|@VERSION@|$version|g" -e "s|@ABI@|$abi|g" -e "s|@STATIC_LIBS@|${static_libs//-l/}|g" \
  sdk-c-api/install/hybrid_rtConfig.cmake.in > "$prefix/lib/cmake/hybrid_rt/hybrid_rtConfig.cmake"
sed -e "s|@VERSION@|$version|g" -e "s|@MAJOR@|$major|g" -e "s|@MINOR@|$minor|g" \
  sdk-c-api/install/hybrid_rtConfigVersion.cmake.in > "$prefix/lib/cmake/hybrid_rt/hybrid_rtConfigVersion.cmake"
echo "install-c: hybrid_rt $version (SONAME libhybrid_rt.so.$abi) in $prefix"
