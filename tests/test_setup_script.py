"""scripts/setup.sh refuses what it cannot use in one line, before installing anything, and
never deletes a virtual environment it did not make (issue 30). The install itself is what
.ci/run does first (and checks that the interpreter's own packages did not change); the
wheel outside the source tree is tests/test_wheel.py."""

import os
import re
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def clone(tmp_path):
    """A folder with only scripts/setup.sh: the script works in the folder above it."""
    (tmp_path / "scripts").mkdir()
    shutil.copy2(ROOT / "scripts" / "setup.sh", tmp_path / "scripts" / "setup.sh")
    return tmp_path


def _stub_python(path: Path, version: str) -> Path:
    """An interpreter that says it is ``version`` and fails every -c check, as 3.10 does
    the >= 3.11 one."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f'#!/bin/sh\n[ "$1" = "-V" ] && {{ echo "Python {version}"; exit 0; }}\nexit 1\n')
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return path


def _setup(clone, *args, python):
    env = {**os.environ, "PYTHON": str(python)}
    return subprocess.run(["bash", str(clone / "scripts" / "setup.sh"), *args], cwd=clone,
                          env=env, capture_output=True, text=True, timeout=120)


def test_a_python_older_than_311_is_refused_in_one_line(clone, tmp_path):
    old = _stub_python(tmp_path / "old" / "python3", "3.10.13")
    res = _setup(clone, python=old)
    assert res.returncode == 2 and res.stdout == ""
    assert res.stderr.splitlines() == [
        f"setup: trussid needs Python >= 3.11; '{old}' is Python 3.10.13 "
        "(set PYTHON=/path/to/python3.11 or newer)"]
    assert not (clone / ".venv").exists()


def test_an_unknown_extra_is_refused(clone):
    res = _setup(clone, "tests", python=sys.executable)
    assert res.returncode == 2 and "unknown extra 'tests'" in res.stderr


@pytest.mark.parametrize("venv_python", ["broken", "3.10"])
def test_an_unusable_venv_is_named_and_kept(clone, venv_python):
    """A .venv whose interpreter was removed, or one too old: the user's to delete."""
    py = clone / ".venv" / "bin" / "python"
    if venv_python == "broken":
        py.parent.mkdir(parents=True)
        py.symlink_to(clone / "no-such-python")
    else:
        _stub_python(py, "3.10.13")
    res = _setup(clone, python=sys.executable)
    assert res.returncode == 2 and len(res.stderr.splitlines()) == 1
    assert res.stderr.startswith("setup: .venv ") and "delete .venv and rerun" in res.stderr
    assert py.is_symlink() or py.exists()


def test_setup_never_breaks_system_packages():
    """pip runs only as the venv's ("$venv/bin/python" -m pip), never as a bare pip or the
    starting interpreter's, and never with --break-system-packages."""
    code = [ln for ln in (ROOT / "scripts" / "setup.sh").read_text().splitlines()
            if not ln.lstrip().startswith("#")]
    assert not any("--break-system-packages" in ln for ln in code)
    assert all('"$venv/bin/python" -m pip' in ln for ln in code if "-m pip" in ln)
    assert not any(re.match(r"\s*(\$sudo\s+|sudo\s+)?pip3?\s", ln) for ln in code)
