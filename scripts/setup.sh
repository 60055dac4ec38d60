#!/usr/bin/env bash
# Installs everything trussid needs on a fresh Debian/Ubuntu machine: the system libraries
# VTK needs to render offscreen (no X server, no GPU), then the package itself.
# Usage: bash scripts/setup.sh [test|bench]   (extras to install beside the package)
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${1:-}"
if command -v apt-get >/dev/null 2>&1; then
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    pkgs="libgl1 libglx-mesa0 libosmesa6 libegl1 libxrender1 libxext6 libgomp1"
    missing=""
    for p in $pkgs; do dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"; done
    if [ -n "$missing" ]; then
        echo "setup: installing system packages:$missing"
        $sudo apt-get update -qq
        DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $missing >/dev/null
    fi
fi
python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore \
    -e ".${extras:+[$extras]}"
