#!/usr/bin/env bash
# Installs everything trussid needs on a fresh Debian/Ubuntu machine: the system libraries
# VTK needs to render offscreen (no X server, no GPU), then the package itself.
# Usage: bash scripts/setup.sh [test|bench|docs]   (extras to install beside the package;
# test includes docs: the suite builds the documentation site)
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${1:-}"
if command -v apt-get >/dev/null 2>&1; then
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    # VTK (PyPI wheels >= 9.4) loads its OpenGL backend at run time; fem.render asks for
    # OSMesa (software llvmpipe, no X server, no GPU), which needs only libosmesa6 (its
    # dependencies libglapi-mesa and libllvm15 come with it). No libGL/libEGL/X11 library is
    # loaded on that path. libgomp1 is not for VTK; kept from the original list.
    pkgs="libosmesa6 libgomp1"
    # The documentation site serves MathJax itself (docs/conf.py), so that its formulas
    # render offline: Debian's MathJax 2.7 (docs and test build the site).
    case "$extras" in docs|test) pkgs="$pkgs libjs-mathjax" ;; esac
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
# slycot (trussid.lqg's MIMO disk margins): its wheel declares numpy>=2, pyNastran numpy<2;
# the wheel runs on numpy 1.26, so it is installed without dependency resolution.
python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore \
    --no-deps "slycot==0.7.1"
