"""The testbed's perturbed truths: the default testbed with one parameter changed each, on
which a controller designed from the nominal identification is graded (issue 14).
"""

from __future__ import annotations

from trussid.geometry.spec import Testbed

from .plant import testbed_plant

__all__ = ["PERTURBATIONS", "STRETCH", "perturbed_testbed", "truths"]

#: (label, Testbed.replace() changes as factors of the nominal value or absolute values)
PERTURBATIONS = (
    ("nominal", {}),
    ("UDF mass +5 %", {"udf__mass": ("x", 1.05)}),
    ("UDF mass -5 %", {"udf__mass": ("x", 0.95)}),
    ("strut E +5 %", {"struts__youngs_modulus": ("x", 1.05)}),
    ("strut E -5 %", {"struts__youngs_modulus": ("x", 0.95)}),
    ("amplifier low-pass 100 Hz", {"filters__lowpass_cutoff": ("=", 100.0)}),
    ("amplifier gain x1.5", {"electrics__amplifier_gain": ("x", 1.5)}),
    ("modal damping 0.1 %", {"damping__modal_ratio": ("=", 0.001)}),
)
#: The stretch cases: at -10 % the 220 Hz mode merges with the strut second-bending family.
STRETCH = (
    ("UDF mass +10 %", {"udf__mass": ("x", 1.10)}),
    ("UDF mass -10 %", {"udf__mass": ("x", 0.90)}),
)


def perturbed_testbed(tb, changes: dict):
    """``tb`` with the changes of one :data:`PERTURBATIONS` entry applied.

    Parameters
    ----------
    tb : trussid.geometry.Testbed
    changes : dict
        ``{"section__field": ("x", factor) or ("=", value)}``.
    """
    kw = {}
    for key, (op, value) in changes.items():
        section, name = key.split("__")
        kw[key] = getattr(getattr(tb, section), name) * value if op == "x" else value
    return tb.replace(**kw) if kw else tb


def truths(tb=None, stretch: bool = False, progress=None) -> list:
    """``[(label, discrete plant)]``: the nominal truth then each perturbed one.

    Parameters
    ----------
    tb : trussid.geometry.Testbed, optional
        Default the default testbed.
    stretch : bool
        Add the :data:`STRETCH` cases.
    progress : callable, optional
        Called with a one-line message per truth built.
    """
    tb = tb or Testbed()
    out = []
    for label, changes in PERTURBATIONS + (STRETCH if stretch else ()):
        out.append((label, testbed_plant(perturbed_testbed(tb, changes)).discrete))
        if progress:
            progress(f"truth: {label} ({out[-1][1].nstates} states)")
    return out
