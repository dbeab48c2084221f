#!/usr/bin/env bash
# System packages the project needs beyond Python: the AVR toolchain and Arduino core to build the
# Mega2560 firmware, and simavr to run it (tests talk to it over a real pseudo-terminal); Debian's chromium, node
# and npm for tests/browser (Foxglove Studio in a real browser, @mcap/core), whose npm packages come pinned by
# tests/browser/package-lock.json.
set -euo pipefail
pkgs=(gcc-avr avr-libc arduino-core-avr simavr libsimavr-dev libelf-dev pkg-config make chromium)
command -v node >/dev/null && command -v npm >/dev/null || pkgs+=(nodejs npm)  # the image's node 20, else Debian's
missing=()
for p in "${pkgs[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi
npm ci --prefix "$(dirname "$0")/../tests/browser" --no-audit --no-fund --loglevel=error
