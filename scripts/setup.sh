#!/usr/bin/env bash
# Installs everything trussid needs into a virtual environment in the clone (.venv), on a
# fresh Debian/Ubuntu machine or any other with Python >= 3.11:
#   - the system packages (apt-get, when it is there): the libraries VTK needs to render
#     offscreen (no X server, no GPU) and, where the system Python lacks it, the venv module;
#   - the virtual environment .venv (created, or reused when it already runs), so that the
#     interpreter's own packages are never changed: a stock Debian/Ubuntu Python is
#     "externally managed" (PEP 668) and refuses pip outside a virtual environment, and any
#     other may hold another tool's packages (never --break-system-packages);
#   - the package, editable, with the extras asked for.
# Usage: bash scripts/setup.sh [test|bench|docs|cluster]   (test includes docs: the suite
# builds the documentation site). PYTHON=/path/to/python3.X picks the interpreter (default:
# python3, or the newest python3.11-3.14 on PATH when python3 is older). Python 3.11-3.14.
# Afterwards: .venv/bin/trussid ..., .venv/bin/python -m pytest ...
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${1:-}"
case "$extras" in ""|test|bench|docs|cluster) ;;
    *) echo "setup: unknown extra '$extras' (use test, bench, docs or cluster)" >&2; exit 2 ;;
esac
# The interpreter: $PYTHON, else python3 when it is >= 3.11, else the newest python3.1X on PATH.
# It is only used to create the venv: nothing is installed into it (it may be externally
# managed, PEP 668, or another tool's).
new_enough() { "$1" -c 'import sys; sys.exit(sys.version_info < (3, 11))' >/dev/null 2>&1; }
if [ -n "${PYTHON:-}" ]; then
    python="$PYTHON"
else
    python=python3
    if ! new_enough python3; then
        for cand in python3.14 python3.13 python3.12 python3.11; do
            if command -v "$cand" >/dev/null 2>&1 && new_enough "$cand"; then python="$cand"; break; fi
        done
    fi
fi
command -v "$python" >/dev/null 2>&1 || { echo "setup: no '$python' on PATH; trussid needs Python 3.11 to 3.14 (set PYTHON=/path/to/python3.X)" >&2; exit 2; }
if ! new_enough "$python"; then
    echo "setup: trussid needs Python >= 3.11; '$python' is $("$python" -V 2>&1) (set PYTHON=/path/to/python3.11 or newer)" >&2
    exit 2
fi
pyver="$("$python" -c 'import sys; print(f"{sys.version_info[0]}.{sys.version_info[1]}")')"

# An existing .venv is checked before anything is installed.
venv=".venv"
reuse=0
if [ -e "$venv" ] || [ -L "$venv" ]; then
    reuse=1
    # reused as it is (a rerun adds extras and updates the package); one that does not run or
    # is too old is the user's to remove: this script deletes nothing it did not make now
    if ! [ -x "$venv/bin/python" ] || ! "$venv/bin/python" -c 'import pip' >/dev/null 2>&1; then
        echo "setup: $venv exists but $venv/bin/python does not run with pip (its interpreter moved or was removed?); delete $venv and rerun" >&2
        exit 2
    fi
    if ! new_enough "$venv/bin/python"; then
        echo "setup: $venv runs $("$venv/bin/python" -V 2>&1), trussid needs >= 3.11; delete $venv and rerun" >&2
        exit 2
    fi
fi

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
    # The test suite opens the demo's report.html in a real browser, offline (headless
    # Chromium in a network namespace: tests/campaign/test_html_report.py).
    case "$extras" in test) pkgs="$pkgs chromium" ;; esac
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
        if [ -n "$sudo" ] && ! command -v sudo >/dev/null 2>&1; then
            echo "setup: these system packages are missing and there is no sudo: install them as root (apt-get install$missing), then rerun" >&2
            exit 2
        fi
        echo "setup: installing system packages:$missing"
        { $sudo apt-get update -qq && DEBIAN_FRONTEND=noninteractive \
            $sudo apt-get install -y -qq --no-install-recommends $missing >/dev/null; } ||
            { echo "setup: apt-get could not install$missing; install them, then rerun" >&2; exit 2; }
    fi
fi

if [ "$reuse" = 1 ]; then
    echo "setup: reusing $venv ($("$venv/bin/python" -V 2>&1))"
else
    echo "setup: creating $venv with $("$python" -V 2>&1) ($(command -v "$python"))"
    "$python" -m venv "$venv" ||
        { rm -rf "$venv"; echo "setup: '$python -m venv' failed; install your system's venv package (Debian/Ubuntu: python${pyver}-venv)" >&2; exit 2; }
fi
pip=("$venv/bin/python" -m pip --disable-pip-version-check --quiet)
"${pip[@]}" install --upgrade pip
"${pip[@]}" install -e ".${extras:+[$extras]}"
echo "setup: done; run trussid as $venv/bin/trussid (or: source $venv/bin/activate)"
