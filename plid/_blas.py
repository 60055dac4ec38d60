"""Run the per-sample recursion with single-threaded BLAS.

The PLID recursion calls BLAS thousands of times a second on matrices of a few hundred
rows. Multi-threaded OpenBLAS only adds synchronisation there, and on a loaded machine it
is disastrous: on the shared 2-core development machine the 30-state MIMO square-root
form ran at 23 samples/s with OpenBLAS threads and 452 samples/s without.

``threadpoolctl`` does this properly but is not a dependency, so this is the small part
of it we need: find the OpenBLAS libraries numpy and scipy loaded (Linux
``/proc/self/maps``), and call their ``*openblas_set_num_threads*`` through ctypes. Where
that is not possible (other platforms, other BLAS) it does nothing.
"""

from __future__ import annotations

import contextlib
import ctypes

__all__ = ["blas_threads"]

_PREFIXES = ("", "scipy_")
_SUFFIXES = ("", "64_", "_64")
_cache: list | None = None


def _controls() -> list:
    global _cache
    if _cache is not None:
        return _cache
    found = []
    try:
        with open("/proc/self/maps") as fh:
            paths = {line.split()[-1] for line in fh if "openblas" in line.lower()}
    except OSError:
        paths = set()
    for path in sorted(paths):
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for pre in _PREFIXES:
            for suf in _SUFFIXES:
                get = getattr(lib, f"{pre}openblas_get_num_threads{suf}", None)
                set_ = getattr(lib, f"{pre}openblas_set_num_threads{suf}", None)
                if get is not None and set_ is not None:
                    get.restype = ctypes.c_int
                    set_.argtypes = [ctypes.c_int]
                    found.append((get, set_))
                    break
            else:
                continue
            break
    _cache = found
    return found


@contextlib.contextmanager
def blas_threads(n: int | None):
    """Limit OpenBLAS to ``n`` threads inside the block (None: leave unchanged)."""
    if n is None:
        yield
        return
    ctrls = _controls()
    saved = [get() for get, _ in ctrls]
    try:
        for _, set_ in ctrls:
            set_(int(n))
        yield
    finally:
        for (_, set_), k in zip(ctrls, saved):
            set_(k)
