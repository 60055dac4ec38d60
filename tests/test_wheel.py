"""The built wheel installs and runs on every Python 3.11-3.14 at hand, with numpy 2 (issue 30).

What an editable install hides: a package left out of the wheel (trussid.adapt and
trussid.updating were, and `trussid demo` ended in ModuleNotFoundError), a dependency that
setup.sh installs beside pip (slycot was), a requirement that does not resolve from binary
wheels on a newer Python (pyNastran's numpy<2 made pip build numpy 1.26 from source on 3.13).
So: the wheel is built from a copy of the sources, installed with plain ``pip install`` (binary
wheels only) into a fresh virtual environment outside the source tree for each interpreter
found, and there ``trussid --version``, ``trussid modes`` on a deck with an INCLUDE (first two
cantilever bending frequencies against Euler-Bernoulli's closed form) and ``trussid demo
--quick`` run. The versions pip resolved are printed (and written to $TRUSSID_ARTIFACTS when
set). For Python 3.14, when no interpreter is at hand, pip resolves and downloads the wheel's
requirements for 3.14 from binary wheels.
"""

import glob
import json
import math
import os
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MINORS = (11, 12, 13, 14)


PIP_QUIET = ["--disable-pip-version-check", "--quiet"]

pytestmark = pytest.mark.slow  # a wheel build, 3 environments, 3 quick demos: minutes


def _interpreters() -> dict[int, str]:
    """One interpreter per minor version 3.11-3.14: pyenv's, else one on PATH."""
    found = {}
    for minor in MINORS:
        cands = sorted(glob.glob(os.path.expanduser(
            f"~/.pyenv/versions/3.{minor}.*/bin/python3.{minor}")))
        which = shutil.which(f"python3.{minor}")
        for cand in cands[::-1] + ([which] if which else []):
            if _runs(cand, minor):
                found[minor] = cand
                break
    return found


def _runs(python: str, minor: int) -> bool:
    try:
        res = subprocess.run([python, "-c", "import sys, venv; print(sys.version_info[1])"],
                             capture_output=True, text=True, timeout=60)
    except OSError:
        return False
    return res.returncode == 0 and res.stdout.strip() == str(minor)


def _env() -> dict:
    """The environment of the installed tool: nothing from this source tree or this venv."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    env["OMP_NUM_THREADS"] = env["OPENBLAS_NUM_THREADS"] = "1"
    return env


def _run(cmd, cwd, timeout=1800) -> subprocess.CompletedProcess:
    res = subprocess.run([str(c) for c in cmd], cwd=cwd, env=_env(), capture_output=True,
                         text=True, timeout=timeout)
    assert res.returncode == 0, f"{cmd}\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}"
    return res


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel, built with build isolation from a copy of what setup.py and pyproject.toml
    name (so that no build/ or egg-info lands in the source tree)."""
    src = tmp_path_factory.mktemp("src")
    for name in ("pyproject.toml", "setup.py", "README.md", "LICENSE"):
        shutil.copy2(ROOT / name, src / name)
    for folder in ("trussid", "fem", "plid", "geometry"):
        shutil.copytree(ROOT / folder, src / folder,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    dist = tmp_path_factory.mktemp("dist")
    _run([sys.executable, "-m", "pip", *PIP_QUIET, "wheel", "--no-deps", "-w", dist, src],
         cwd=dist)
    (whl,) = dist.glob("trussid-*.whl")
    return whl


def test_the_wheel_holds_every_module_of_the_sources(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    roots = {"trussid": "trussid", "fem": "trussid/fem", "plid": "trussid/plid",
             "geometry": "trussid/geometry"}
    missing = []
    for folder, target in roots.items():
        for path in (ROOT / folder).rglob("*.py"):
            rel = path.relative_to(ROOT / folder).as_posix()
            if "__pycache__" not in rel and f"{target}/{rel}" not in names:
                missing.append(f"{target}/{rel}")
    assert not missing
    from trussid import __version__

    assert wheel.name.startswith(f"trussid-{__version__}-py3-none-any")
    meta = zipfile.ZipFile(wheel).read(f"trussid-{__version__}.dist-info/METADATA").decode()
    assert "\nLicense-Expression: MIT\n" in meta  # SPDX (PEP 639), setuptools >= 77
    requires = re.findall(r"^Requires-Dist: ([A-Za-z0-9_.-]+)", meta, re.M)
    assert "slycot" in requires and "pyNastran" not in requires


def _deck(folder: Path) -> tuple[Path, list[float]]:
    """A steel cantilever, 10 CBARs over 2 m, 20 mm square section, its grids and bars in an
    INCLUDEd file of a subfolder; and the first two bending frequencies [Hz] of
    Euler-Bernoulli's closed form, f = (beta L)^2 / (2 pi L^2) sqrt(E I / (rho A))."""
    n, L, E, rho, a = 10, 2.0, 210e9, 7800.0, 0.02
    A, I = a * a, a ** 4 / 12
    (folder / "parts").mkdir(parents=True)
    (folder / "parts" / "beam.bdf").write_text(
        "$ the beam: grids and bars\n"
        + "".join(f"GRID,{i + 1},,{L * i / n!r},0.,0.\n" for i in range(n + 1))
        + "".join(f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,1.,0.\n" for i in range(n)))
    deck = folder / "cantilever.bdf"
    deck.write_text("SOL 103\nCEND\nSUBCASE 1\n  METHOD = 1\n  SPC = 1\nBEGIN BULK\n"
                    "PARAM,COUPMASS,1\nEIGRL,1,,,2\n"
                    f"MAT1,1,{E:.6e},,0.3,{rho:.1f}\n"
                    f"PBAR,1,1,{A:.8e},{I:.10e},{I:.10e},{2.25 * a ** 4 / 16:.8e}\n"
                    "SPC1,1,123456,1\nINCLUDE 'parts/beam.bdf'\nENDDATA\n")
    f1 = 1.8751040687 ** 2 / (2 * math.pi * L ** 2) * math.sqrt(E * I / (rho * A))
    return deck, [f1, f1]  # the square section bends alike in both planes


def _report(text: str, capsys) -> None:
    with capsys.disabled():
        print("\n" + text)
    folder = os.environ.get("TRUSSID_ARTIFACTS")
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        with open(Path(folder) / "wheel_environments.txt", "a") as fh:
            fh.write(text + "\n")


@pytest.mark.parametrize("minor", MINORS)
def test_the_wheel_installs_and_runs_in_a_fresh_environment(wheel, minor, tmp_path, capsys):
    pythons = _interpreters()
    if minor not in pythons:
        pytest.skip(f"no Python 3.{minor} interpreter on this machine")
    work = tmp_path / "work"  # outside the source tree: nothing imports from it
    work.mkdir()
    venv = tmp_path / f"venv-3.{minor}"
    _run([pythons[minor], "-m", "venv", venv], cwd=work)
    py, tool = venv / "bin" / "python", venv / "bin" / "trussid"
    # plain pip (the pip cache is shared between the environments), binary wheels only
    _run([py, "-m", "pip", *PIP_QUIET, "install", "--only-binary=:all:", wheel], cwd=work)
    freeze = _run([py, "-m", "pip", "freeze", "--all"], cwd=work).stdout
    _report(f"== Python 3.{minor} ({pythons[minor]}), the wheel's resolution:\n{freeze}", capsys)
    numpy = re.search(r"^numpy==(\d+)\.", freeze, re.M)
    assert numpy and int(numpy.group(1)) >= 2, freeze
    assert "slycot==" in freeze.lower()
    assert not re.search(r"^pynastran==", freeze, re.M | re.I)  # not a dependency (issue 30)

    from trussid import __version__

    assert _run([tool, "--version"], cwd=work).stdout.strip() == f"trussid {__version__}"
    out = work / "report"
    _run([tool, "demo", "--quick", "--out", out], cwd=work)
    summary = json.loads((out / "summary.json").read_text())
    prov = summary["provenance"]
    assert prov["trussid_version"] == __version__ and prov["python"].startswith(f"3.{minor}.")
    assert prov["commit"] is None  # an installed wheel, not a checkout
    nominal = summary["control"]["rows"]["nominal"]  # the closed loop: slycot, numpy 2
    assert nominal["stable"] and nominal["margins"]["mimo"]["gain_db"] > 0

    deck, f_exact = _deck(work / "deck")
    res = _run([tool, "modes", deck, "--n", "2", "--json"], cwd=work)
    assert json.loads(res.stdout)["frequencies_hz"] == pytest.approx(f_exact, rel=1e-5)


def test_the_requirements_resolve_for_python_314_from_binary_wheels(wheel, tmp_path, capsys):
    """Without a 3.14 interpreter, pip resolves the wheel's requirements for 3.14 (Linux,
    this machine's platform) from binary wheels and downloads them: every dependency has a
    cp314 or pure wheel that admits numpy 2."""
    if 14 in _interpreters():
        pytest.skip("a Python 3.14 interpreter is at hand: the environment test runs on it")
    dest = tmp_path / "wheels"
    _run([sys.executable, "-m", "pip", *PIP_QUIET, "download", "--only-binary=:all:",
          "--python-version", "3.14", "--dest", dest, wheel], cwd=tmp_path)
    files = sorted(p.name for p in dest.glob("*.whl"))
    _report("== Python 3.14 (pip download --only-binary=:all: --python-version 3.14):\n"
            + "\n".join(files), capsys)
    numpy = [f for f in files if f.startswith("numpy-")]
    assert len(numpy) == 1 and int(numpy[0].split("-")[1].split(".")[0]) >= 2
    assert any(f.startswith("slycot-") and "cp314" in f for f in files), files
    assert not any(f.lower().startswith("pynastran-") for f in files)
