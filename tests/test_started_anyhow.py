"""The suite does not depend on how it is started (issue 30).

A shell without job control starts a background job (``cmd &``, ``nohup``, a batch script)
with SIGINT ignored, and Python then keeps it ignored: tests that interrupt the code under
test with a real SIGINT failed there (9 failures in the newcomer's background run) while
passing in a terminal. Those tests install Python's own handler for themselves; this runs
them in a child started with SIGINT ignored, as such a job starts it. (.ci/run runs the
whole suite so.)
"""

import signal
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: The test files that send SIGINT to their own process.
SIGNAL_TESTS = ["tests/campaign/test_report_integrity.py"]

CHILD = """
import signal, sys
# what the child inherited, before pytest or anything else touches it
assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN, signal.getsignal(signal.SIGINT)
import pytest
sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", "-m", "slow or not slow", *sys.argv[1:]]))
"""


def _ignore_sigint():
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def test_the_signal_tests_pass_when_started_with_sigint_ignored():
    res = subprocess.run([sys.executable, "-c", CHILD, *SIGNAL_TESTS], cwd=ROOT,
                         preexec_fn=_ignore_sigint, capture_output=True, text=True,
                         timeout=600)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    assert " passed" in res.stdout and "failed" not in res.stdout


def test_every_test_that_signals_itself_is_run_so():
    """A new test file that sends its own process SIGINT is added to SIGNAL_TESTS."""
    needles = ("os.getpid(), signal." + "SIGINT", "raise_signal(signal." + "SIGINT")  # not this file
    found = {path.relative_to(ROOT).as_posix() for path in (ROOT / "tests").rglob("test_*.py")
             if any(n in path.read_text() for n in needles)}
    assert found == set(SIGNAL_TESTS)
