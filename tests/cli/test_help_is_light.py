"""``trussid --help`` and each command's ``--help`` import no heavy library: the command
modules defer their library imports into ``run()`` (docs/architecture.md: measured 0.17 s of
CPU for ``trussid --help`` against 2.4 s with the library modules imported first)."""

import subprocess
import sys

HEAVY = ("control", "vtk", "pyvista", "pyNastran", "matplotlib", "trimesh", "dask", "distributed",
         "pandas", "scipy")


def _loaded_after(argv: list[str]) -> list[str]:
    code = ("import sys\nfrom trussid.cli import main\ntry:\n    main(%r)\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in %r if m in sys.modules))" % (argv, HEAVY))
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return res.stdout.strip().splitlines()[-1]


def test_top_level_help_imports_no_heavy_library():
    assert _loaded_after(["--help"]) == "[]"


def test_a_command_help_imports_no_heavy_library():
    for command in ("identify", "plant", "demo"):
        assert _loaded_after([command, "--help"]) == "[]", command
