#!/usr/bin/env bash
# Installs what building and testing hybrid-rt needs, and nothing when it is already there.
#
#  - a Vulkan device with ray tracing: a real GPU driver if one is present, otherwise Mesa's
#    lavapipe (CPU) from Mesa >= 24.1. Debian 12's own Mesa (22.3) has no ray tracing, so the
#    Mesa packages come from bookworm-backports (Mesa 25.x). The backports source is derived
#    from the machine's existing Debian source list, so no package host is written here.
#  - glslangValidator (shader compiler) and spirv-val (shader validator)
#  - the Khronos validation layer, so tests fail on validation errors
#  - a C compiler and the Vulkan headers/loader (libvulkan-dev), for the C ABI test, and
#    pkg-config and CMake, which build the C sample against the installed C library
#  - Xvfb and the X11 client libraries winit loads at run time, so the sample's window path
#    is tested without a display
#
# Usage: source it (`. scripts/setup.sh`) or run it. Idempotent. Needs root (or sudo) only
# when something is missing.
set -euo pipefail

log() { printf '[setup] %s\n' "$*" >&2; }

if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi

have_cmd() { command -v "$1" >/dev/null 2>&1; }

# True when some installed Vulkan driver reports VK_KHR_ray_tracing_pipeline.
have_rt_vulkan() {
  have_cmd vulkaninfo || return 1
  # Capture first: `vulkaninfo | grep -q` would die of SIGPIPE under pipefail.
  local info
  info=$(vulkaninfo 2>/dev/null) || true
  grep -q 'VK_KHR_ray_tracing_pipeline' <<<"$info"

}

apt_updated=0
apt_install() {
  if [ "$apt_updated" -eq 0 ]; then
    log "apt-get update"
    $SUDO apt-get update -qq
    apt_updated=1
  fi
  log "apt-get install $*"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "$@" >/dev/null
}

# Write a bookworm-backports source that reuses the URI of the machine's own Debian source.
ensure_backports_source() {
  local target=/etc/apt/sources.list.d/hybrid-rt-backports.sources
  [ -f "$target" ] && return 0
  if grep -rqs 'bookworm-backports' /etc/apt/sources.list /etc/apt/sources.list.d/ ; then
    return 0
  fi
  local uri="" keyring="/usr/share/keyrings/debian-archive-keyring.gpg"
  if [ -f /etc/apt/sources.list.d/debian.sources ]; then
    # deb822: the first URIs line of the stanza whose Suites has plain "bookworm".
    uri=$(awk '/^URIs:/{u=$2} /^Suites:/ && / bookworm( |$)/{print u; exit}' \
      /etc/apt/sources.list.d/debian.sources)
  fi
  if [ -z "$uri" ] && [ -f /etc/apt/sources.list ]; then
    uri=$(awk '$1=="deb" && $3=="bookworm"{for(i=2;i<=NF;i++) if($i ~ /^[a-z]+:\/\//){print $i; exit}}' \
      /etc/apt/sources.list)
  fi
  if [ -z "$uri" ]; then
    log "no Debian bookworm source found in /etc/apt; cannot derive bookworm-backports"
    return 1
  fi
  log "adding bookworm-backports from $uri"
  printf 'Types: deb\nURIs: %s\nSuites: bookworm-backports\nComponents: main\nSigned-By: %s\n' \
    "$uri" "$keyring" | $SUDO tee "$target" >/dev/null
  apt_updated=0
}

main() {
  local pkgs=()
  have_cmd glslangValidator || pkgs+=(glslang-tools)
  have_cmd spirv-val || pkgs+=(spirv-tools)
  have_cmd cc || pkgs+=(gcc libc6-dev)
  # A C++ translation unit includes the header in the C tests.
  have_cmd c++ || pkgs+=(g++)
  have_cmd vulkaninfo || pkgs+=(vulkan-tools)
  [ -e /usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json ] \
    || pkgs+=(vulkan-validationlayers)
  [ -e /usr/include/vulkan/vulkan.h ] || pkgs+=(libvulkan-dev)
  # The C install tree is checked by building the C sample with pkg-config and with CMake.
  have_cmd pkg-config || pkgs+=(pkg-config)
  have_cmd cmake || pkgs+=(cmake)
  have_cmd Xvfb || pkgs+=(xvfb)
  # winit's X11 backend dlopens these (no -dev packages: nothing links against them).
  local lib known
  # Captured once, not piped into grep -q (SIGPIPE under pipefail).
  known=$(ldconfig -p 2>/dev/null || /sbin/ldconfig -p 2>/dev/null || true)
  for lib in libX11-xcb.so.1:libx11-xcb1 libXcursor.so.1:libxcursor1 libXrandr.so.2:libxrandr2 \
             libXi.so.6:libxi6 libxkbcommon-x11.so.0:libxkbcommon-x11-0; do
    grep -q "${lib%%:*}" <<<"$known" || pkgs+=("${lib##*:}")
  done
  if [ ${#pkgs[@]} -gt 0 ]; then apt_install "${pkgs[@]}"; fi

  if ! have_rt_vulkan; then
    if [ -r /etc/os-release ] && grep -q 'VERSION_CODENAME=bookworm' /etc/os-release; then
      ensure_backports_source
      apt_install -t bookworm-backports mesa-vulkan-drivers
    else
      apt_install mesa-vulkan-drivers
    fi
    if ! have_rt_vulkan; then
      log "no Vulkan driver with VK_KHR_ray_tracing_pipeline after installing Mesa"
      vulkaninfo --summary >&2 || true
      return 1
    fi
  fi
  if ! have_cmd cargo; then
    log "cargo not found: install a Rust toolchain (rustup) first"
    return 1
  fi
  log "ready: $(vulkaninfo --summary 2>/dev/null | grep -m3 -E 'deviceName' | sed 's/^ *//' | tr '\n' ' ')"
}

main "$@"
