"""One BLAS thread per command by default, overridable (issue 19, acceptance 5).

The timings that motivate it are in benchmarks/results/threads.md (a test never asserts
wall-clock time)."""

import subprocess
import sys

import pytest

from trussid._util.threads import blas_env, blas_thread_counts, threads_setting
from trussid.cli import main


@pytest.mark.parametrize("value, environ, expected", [
    (None, {}, 1),                                        # the default
    (None, {"TRUSSID_THREADS": "3"}, 3),                  # the environment variable
    ("2", {"TRUSSID_THREADS": "3"}, 2),                   # the option wins
    (None, {"OPENBLAS_NUM_THREADS": "4"}, None),          # the user's own BLAS setting stays
    (None, {"TRUSSID_THREADS": "2", "OMP_NUM_THREADS": "4"}, 2),
    (0, {}, None),                                        # 0: no limit
])
def test_threads_setting_precedence(value, environ, expected):
    assert threads_setting(value, environ) == expected


@pytest.mark.parametrize("value", ["-1", "two"])
def test_threads_setting_refuses_nonsense(value):
    with pytest.raises(ValueError, match="whole number >= 0"):
        threads_setting(None, {"TRUSSID_THREADS": value})


def test_blas_env_covers_openblas_openmp_and_mkl():
    assert blas_env(1) == {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
                           "MKL_NUM_THREADS": "1"}


def _spy(monkeypatch):
    """Replace ``trussid modes`` by a function that records the BLAS thread counts."""
    import trussid.cli.commands.modes as modes

    seen = []
    monkeypatch.setattr(modes, "run", lambda args: seen.append(blas_thread_counts()) or 0)
    return seen


def test_every_command_runs_with_one_blas_thread_by_default(monkeypatch):
    monkeypatch.delenv("TRUSSID_THREADS", raising=False)
    for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        monkeypatch.delenv(k, raising=False)
    from trussid._util.threads import blas_threads

    seen = _spy(monkeypatch)
    with blas_threads(2):  # the caller's setting, whatever the test process started with
        # (a BLAS built for one thread, as cvxopt's wheel is, stays at 1)
        inside = blas_thread_counts()
        assert 2 in inside
        assert main(["modes"]) == 0
        assert blas_thread_counts() == inside  # scoped: the caller's setting is back
    assert seen[0] and set(seen[0]) == {1}


def test_threads_option_and_variable_override_the_default(monkeypatch):
    seen = _spy(monkeypatch)
    monkeypatch.setenv("TRUSSID_THREADS", "2")
    assert main(["modes"]) == 0
    assert main(["--threads", "1", "modes"]) == 0
    # 2 where a library can run two threads (cvxopt's single-threaded BLAS stays at 1)
    assert 2 in seen[0] and set(seen[0]) <= {1, 2} and set(seen[1]) == {1}


def test_the_command_line_entry_limits_blas_libraries_loaded_later():
    """scipy loads its own OpenBLAS on first use, after the limit: the entry point sets the
    BLAS variables for its own process so that those libraries start with one thread too."""
    code = ("import sys; from trussid.cli import _early_threads; _early_threads(sys.argv[1:]); "
            "import os, scipy.linalg; from trussid._util.threads import blas_thread_counts; "
            "print(os.environ.get('OPENBLAS_NUM_THREADS'), set(blas_thread_counts()))")
    res = subprocess.run([sys.executable, "-c", code, "modes"], capture_output=True, text=True,
                         env={"PATH": "/usr/bin:/bin"}, check=True)
    assert res.stdout.strip() == "1 {1}"
