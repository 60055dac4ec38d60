#!/usr/bin/env bash
# Installs everything trussid needs into a virtual environment in the clone (.venv), on a
# fresh Debian/Ubuntu machine or any other with Python >= 3.11:
#   - the system packages (apt-get, when it is there): the libraries VTK needs to render
#     offscreen (no X server, no GPU) and, where the system Python lacks it, the venv module;
#   - the virtual environment .venv (created, or reused when it already runs), so that the
#     interpreter's own packages are never changed: a stock Debian/Ubuntu Python is
#     "externally managed" (PEP 668) and refuses pip outside a virtual environment;
#   - the package, editable, with the extras asked for.
# Usage: bash scripts/setup.sh [test|bench|docs]   (test includes docs: the suite builds the
# documentation site). PYTHON=/path/to/python3.X picks the interpreter (default: python3).
# Afterwards: .venv/bin/trussid ..., .venv/bin/python -m pytest ...
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${1:-}"
case "$extras" in ""|test|bench|docs|cluster) ;;
    *) echo "setup: unknown extra '$extras' (use test, bench, docs or cluster)" >&2; exit 2 ;;
esac
python="${PYTHON:-python3}"
command -v "$python" >/dev/null 2>&1 || { echo "setup: no '$python' on PATH (set PYTHON=/path/to/python3.11 or newer)" >&2; exit 2; }
if ! "$python" -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
    echo "setup: trussid needs Python >= 3.11; '$python' is $("$python" -V 2>&1) (set PYTHON=...)" >&2
    exit 2
fi
pyver="$("$python" -c 'import sys; print(f"{sys.version_info[0]}.{sys.version_info[1]}")')"

if command -v apt-get >/dev/null 2>&1 && command -v dpkg >/dev/null 2>&1; then
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    # VTK (PyPI wheels >= 9.4) loads its OpenGL backend at run time; fem.render asks for
    # OSMesa (software llvmpipe, no X server, no GPU), which needs only libosmesa6 (its
    # dependencies libglapi-mesa and libllvm15 come with it). libgomp1: OpenMP runtime.
    pkgs="libosmesa6 libgomp1"
    # The documentation site serves MathJax itself (docs/conf.py), so that its formulas
    # render offline: Debian's MathJax 2.7 (docs and test build the site).
    case "$extras" in docs|test) pkgs="$pkgs libjs-mathjax" ;; esac
    # Debian's and Ubuntu's own Python ships venv without ensurepip: python3.X-venv adds it.
    # Only for the system interpreter (a pyenv or conda Python has its own).
    if ! "$python" -c 'import ensurepip, venv' >/dev/null 2>&1; then
        case "$("$python" -c 'import sys; print(sys.prefix)')" in
            /usr) pkgs="$pkgs python${pyver}-venv" ;;
        esac
    fi
    missing=""
    for p in $pkgs; do dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"; done
    if [ -n "$missing" ]; then
        echo "setup: installing system packages:$missing"
        $sudo apt-get update -qq
        DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $missing >/dev/null
    fi
fi

venv=".venv"
if [ -x "$venv/bin/python" ] && "$venv/bin/python" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
    echo "setup: reusing $venv ($("$venv/bin/python" -V 2>&1))"
else
    rm -rf "$venv"
    echo "setup: creating $venv with $("$python" -V 2>&1) ($(command -v "$python"))"
    "$python" -m venv "$venv" || { echo "setup: '$python -m venv' failed; install your system's venv package (Debian/Ubuntu: python${pyver}-venv)" >&2; exit 2; }
fi
pip=("$venv/bin/python" -m pip --disable-pip-version-check --quiet)
"${pip[@]}" install --upgrade pip
"${pip[@]}" install -e ".${extras:+[$extras]}"
echo "setup: done; run trussid as $venv/bin/trussid (or: source $venv/bin/activate)"
