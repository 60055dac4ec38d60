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


#: Environment variable that sets the BLAS threads of every ``trussid`` command.
THREADS_ENV = "TRUSSID_THREADS"
#: The environment variables BLAS/OpenMP libraries read when they load.
_BLAS_ENV = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def threads_setting(value: int | str | None = None, environ=None) -> int | None:
    """BLAS threads a command should use: ``None`` means "leave the libraries alone".

    Precedence: ``value`` (a ``--threads`` option), then ``TRUSSID_THREADS``, then (if the
    user set ``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS`` or ``MKL_NUM_THREADS``) their
    choice, then 1. A value of 0 means no limit.

    Why 1 by default: the commands do many small dense products (Bode sweeps of a
    141-state plant, PLID updates), where BLAS threads only add synchronisation; on the
    shared 2-core machine ``trussid plant`` took 36 s with OpenBLAS threads and 4.5 s
    without (benchmarks/results/threads.md).

    Raises
    ------
    ValueError
        ``value`` or ``TRUSSID_THREADS`` is not a non-negative integer.
    """
    import os

    env = os.environ if environ is None else environ
    source = "--threads"
    if value is None:
        value, source = env.get(THREADS_ENV), THREADS_ENV
    if value is None or (isinstance(value, str) and not value.strip()):
        if any(env.get(k) for k in _BLAS_ENV):
            return None
        return 1
    try:
        n = int(str(value).strip())
    except ValueError:
        n = -1
    if n < 0:
        raise ValueError(f"{source} must be a whole number >= 0 (0: no limit), got {value!r}")
    return n or None


def blas_env(n: int) -> dict[str, str]:
    """The environment variables that give BLAS libraries ``n`` threads when they load
    (for a process entry point, before numpy is imported; library code never sets them)."""
    return {k: str(int(n)) for k in _BLAS_ENV}
