"""Nothing the installed package runs imports pyNastran (issue 30): in a fresh interpreter
where ``pyNastran`` and ``cpylog`` cannot be imported, every module of the package imports
and ``trussid modes`` reads a deck with an INCLUDE and writes its OP2."""

from __future__ import annotations

import subprocess
import sys
import textwrap

BLOCK = textwrap.dedent("""
    import importlib.abc, sys

    class NoPyNastran(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in ("pyNastran", "cpylog"):
                raise ImportError(f"{name} is made unimportable by this test")
            return None

    sys.meta_path.insert(0, NoPyNastran())
    for name in [m for m in sys.modules if m.split(".")[0] in ("pyNastran", "cpylog")]:
        del sys.modules[name]
""")


def _run(code: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", BLOCK + textwrap.dedent(code)], cwd=cwd, capture_output=True,
                          text=True, timeout=600)


def test_every_module_imports_without_pynastran(tmp_path):
    p = _run("""
        import importlib, pkgutil, trussid
        failed = []
        names = [m.name for m in pkgutil.walk_packages(trussid.__path__, "trussid.")]
        for sub in ("fem", "plid", "geometry"):
            pkg = importlib.import_module("trussid." + sub)
            names += [m.name for m in pkgutil.walk_packages(pkg.__path__, f"trussid.{sub}.")]
        names = [n for n in names if not n.endswith("__main__")]  # those run the CLI
        for name in sorted(set(names)):
            try:
                importlib.import_module(name)
            except Exception as exc:
                failed.append(f"{name}: {type(exc).__name__}: {exc}")
        assert "pyNastran" not in sys.modules and "cpylog" not in sys.modules
        print(len(set(names)))
        print("\\n".join(failed))
    """, tmp_path)
    assert p.returncode == 0, p.stderr
    n, *failed = p.stdout.strip().splitlines()
    assert int(n) > 100  # the whole package was walked (trussid, fem, plid, geometry)
    assert failed == [], "\n".join(failed)


def test_modes_reads_a_deck_with_an_include_without_pynastran(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "beam.bdf").write_text(
        "MAT1,1,200.+9,,0.3,7850.\nPBAR,1,1,2.-4,1.6667-9,6.6667-9,4.5776-9\n"
        + "".join(f"GRID,{i},,{0.25 * (i - 1)!r},0.,0.\n" for i in range(1, 6))
        + "".join(f"CBAR,{e},1,{e},{e + 1},0.,0.,1.\n" for e in range(1, 5)))
    (tmp_path / "cantilever.bdf").write_text(
        "SOL 103\nCEND\nMETHOD = 1\nSPC = 1\nBEGIN BULK\nPARAM,COUPMASS,1\nINCLUDE 'parts/beam.bdf'\n"
        "SPC1,1,123456,1\nEIGRL,1,,,2\nENDDATA\n")
    p = _run("""
        from trussid.cli import main
        code = main(["modes", "cantilever.bdf", "--json", "--op2", "out.op2"])
        assert "pyNastran" not in sys.modules and "cpylog" not in sys.modules
        sys.exit(code)
    """, tmp_path)
    assert p.returncode == 0, p.stderr
    import json

    f = json.loads(p.stdout)["frequencies_hz"]
    # Euler-Bernoulli cantilever, 4 coupled-mass elements: 8.154 and 16.308 Hz (the two
    # bending planes, I2 = 4 I1); beta_1 L = 1.8751
    assert abs(f[0] / 8.1543 - 1) < 2e-3 and abs(f[1] / 16.3086 - 1) < 2e-3
    assert (tmp_path / "out.op2").stat().st_size > 0
