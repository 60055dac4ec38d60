"""One definition of each modal-analysis concept in the library (issue 22, acceptance 3), and
of each closed-loop rule (issue 31, acceptance 2).

A line scan cannot see a semantic duplicate: the frequency response, the MAC, the
frequency and damping of a pole, and the pairing of two sets of modes were each written
two or three times under different names. Each concept is recognised here by what its
code computes (an AST signature, whatever the function is called), and must be computed
in exactly one function: its home in :mod:`trussid.plid`. Everything else calls it.
"""

from __future__ import annotations

import ast
import functools

import pytest

from tests import test_layering as layering


def _calls(node, name: str) -> bool:
    """Whether ``node`` calls a function or method named ``name``."""
    return any(isinstance(n, ast.Call) and (getattr(n.func, "attr", None) == name
                                            or getattr(n.func, "id", None) == name)
               for n in ast.walk(node))


def _is_2j_pi(node) -> bool:
    """``2j * np.pi`` (the imaginary unit of a frequency in Hz)."""
    return (isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult)
            and isinstance(node.left, ast.Constant) and node.left.value == 2j
            and getattr(node.right, "attr", None) == "pi")


def frequency_response(func) -> bool:
    """Evaluates ``C (x I - A)^-1 B`` itself: an eigen- or linear solve on the frequency
    axis ``exp(2j pi f dt)`` / ``2j pi f``."""
    axis = any(_is_2j_pi(n) for n in ast.walk(func))
    return axis and any(_calls(func, f) for f in ("eig", "eigvals", "solve", "inv"))


def mac(func) -> bool:
    """``|a^H b|^2 / (...)``: the square of the magnitude of a matrix product of shapes."""
    for n in ast.walk(func):
        if (isinstance(n, ast.BinOp) and isinstance(n.op, ast.Pow)
                and isinstance(n.left, ast.Call) and getattr(n.left.func, "attr", None) == "abs"
                and n.left.args and isinstance(n.left.args[0], ast.BinOp)
                and isinstance(n.left.args[0].op, ast.MatMult)):
            return True
    return False


def damping_of_pole(func) -> bool:
    """``-Re(s) / |s|``: the damping ratio of a pole."""
    return any(isinstance(n, ast.BinOp) and isinstance(n.op, ast.Div)
               and isinstance(n.left, ast.UnaryOp) and isinstance(n.left.op, ast.USub)
               and getattr(n.left.operand, "attr", None) == "real" for n in ast.walk(func))


def pairing(func) -> bool:
    """A linear assignment (Hungarian) between two sets."""
    return _calls(func, "linear_sum_assignment")


def closed_loop_mode_damping(func) -> bool:
    """The damping of poles of a closed loop: a pole conversion (``freq_damping``,
    ``pole_parameters``) in a function that builds or reads the closed loop
    (``closed_loop(...)``, ``loop.closed``)."""
    converts = _calls(func, "freq_damping") or _calls(func, "pole_parameters")
    closes = _calls(func, "closed_loop") or any(
        isinstance(n, ast.Attribute) and n.attr == "closed" for n in ast.walk(func))
    return converts and closes


@functools.cache
def _functions(path) -> list:
    tree = ast.parse(path.read_text(), filename=str(path))
    return [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]


HOMES = {
    frequency_response: "trussid.plid.frf.frequency_response",
    mac: "trussid.plid.modal.mac",
    damping_of_pole: "trussid.plid.modal.pole_parameters",
    pairing: "trussid.plid.modal.assign_pairs",
    closed_loop_mode_damping: "trussid.lqg.evaluate.damping_table",
}


def definitions(concept, paths=None) -> list[str]:
    """The innermost library functions whose own code computes ``concept``."""
    found = []
    for path in paths or layering.library_files():
        module = layering._module_name(path)
        for func in _functions(path):
            inner = [n for n in ast.walk(func) if n is not func
                     and isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and concept(n)]
            if concept(func) and not inner:
                found.append(f"{module}.{func.name}")
    return sorted(found)


@pytest.mark.parametrize("concept", list(HOMES), ids=lambda c: c.__name__)
def test_each_concept_is_computed_in_one_function(concept):
    assert definitions(concept) == [HOMES[concept]]


@pytest.mark.parametrize("source, concept", [
    ("def resp(sys, f):\n    lam, V = np.linalg.eig(sys.A)\n"
     "    return 1 / (np.exp(2j * np.pi * f * sys.dt) - lam)\n", frequency_response),
    ("def my_mac(a, b):\n    return np.abs(a.conj().T @ b) ** 2 / 4\n", mac),
    ("def fd(z, dt):\n    s = np.log(z) / dt\n    return abs(s), -s.real / abs(s)\n", damping_of_pole),
    ("def match(c):\n    return scipy.optimize.linear_sum_assignment(c)\n", pairing),
    ("def mode_damping(plant, ctrl, f_modes):\n"
     "    lam = np.linalg.eigvals(closed_loop(plant, ctrl).A)\n"
     "    f, z = freq_damping(lam, plant.dt)\n"
     "    return [z[np.argmin(np.abs(f - fi))] for fi in f_modes]\n", closed_loop_mode_damping),
    ("def worst(loop, f0):\n    f, z = freq_damping(np.linalg.eigvals(loop.closed.A), 1e-3)\n"
     "    return z[np.abs(f / f0 - 1) < 0.03].min()\n", closed_loop_mode_damping),
])
def test_a_second_definition_is_caught(tmp_path, monkeypatch, source, concept):
    """The check itself: a copy planted in another module is found beside the home."""
    (tmp_path / "planted.py").write_text("import numpy as np\n\n\n" + source)
    monkeypatch.setitem(layering.SOURCES, "trussid.elsewhere", tmp_path)
    got = definitions(concept)  # the library and the planted module
    name = source.split("(")[0].removeprefix("def ")
    assert got == sorted([HOMES[concept], f"trussid.elsewhere.planted.{name}"])


# --------------------------------------------------------------------------- thresholds


def threshold_classes(paths=None) -> list[str]:
    """Library classes that declare acceptance thresholds of a loop: a numeric default for
    the damping of the dominant modes (a field named ``dominant...`` or ``accept...``) and
    one for the ratio kept by the others (``...ratio...``)."""
    found = []
    for path in paths or layering.library_files():
        module = layering._module_name(path)
        tree = ast.parse(path.read_text(), filename=str(path))
        for cls in (n for n in ast.walk(tree) if isinstance(n, ast.ClassDef)):
            names = [n.target.id for n in cls.body if isinstance(n, ast.AnnAssign)
                     and isinstance(n.target, ast.Name) and isinstance(n.value, ast.Constant)
                     and isinstance(n.value.value, float)]
            if (any(k.startswith(("dominant", "accept")) for k in names)
                    and any("ratio" in k for k in names)):
                found.append(f"{module}.{cls.name}")
    return sorted(found)


def test_the_loop_thresholds_are_declared_once():
    assert threshold_classes() == ["trussid.lqg.grading.Thresholds"]


def test_a_second_set_of_thresholds_is_caught(tmp_path, monkeypatch):
    """The check itself: the supervisor's former settings, planted, are found."""
    (tmp_path / "planted.py").write_text(
        "from dataclasses import dataclass\n\n\n@dataclass(frozen=True)\n"
        "class SupervisorSettings:\n    accept_damping: float = 0.05\n"
        "    others_ratio: float = 0.8\n    min_margin_db: float = 6.0\n")
    monkeypatch.setitem(layering.SOURCES, "trussid.elsewhere", tmp_path)
    assert threshold_classes() == ["trussid.elsewhere.planted.SupervisorSettings",
                                   "trussid.lqg.grading.Thresholds"]
