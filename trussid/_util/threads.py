"""BLAS thread limits around small, repeated linear algebra (via threadpoolctl).

The PLID recursion and the FE eigen/static solutions call BLAS thousands of times on
matrices of a few hundred rows. Multi-threaded OpenBLAS only adds synchronisation there,
and on a loaded machine it is disastrous (measured on the shared 2-core development
machine: the 30-state MIMO square-root PLID ran at 23 samples/s with OpenBLAS threads and
452 samples/s without).
"""

from __future__ import annotations

import contextlib
import functools


@functools.lru_cache(maxsize=1)
def _controller():
    # Created on first use, after numpy and scipy have loaded their BLAS libraries;
    # threadpoolctl's controller caches the library list, so a limit costs ~30 us.
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


@contextlib.contextmanager
def blas_threads(n: int | None):
    """Limit BLAS to ``n`` threads inside the block (``None``: leave it as it is)."""
    if n is None:
        yield
        return
    with _controller().limit(limits=int(n), user_api="blas"):
        yield


def blas_thread_counts() -> list[int]:
    """Current thread count of every BLAS library loaded (for tests and reports)."""
    return [lib.num_threads for lib in _controller().select(user_api="blas").lib_controllers]


def forget_blas_libraries() -> None:
    """Rescan the loaded BLAS libraries at the next limit: call it after importing a package
    that brings its own BLAS (cvxopt), or the limit will not reach that library."""
    _controller.cache_clear()
