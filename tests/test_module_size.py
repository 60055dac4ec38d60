"""No module of the library is over 700 lines (issue 31, acceptance 3).

A module that long holds more than one job; the split ones keep their public names
importable from where they were (re-exports), so the limit costs no caller anything.
"""

from __future__ import annotations

from tests import test_layering as layering

#: Most lines a library module may have.
MAX_LINES = 700

def too_long(paths=None) -> list[str]:
    """``path: N lines`` for every library module over :data:`MAX_LINES`."""
    found = []
    for path in paths or layering.library_files():
        n = len(path.read_text().splitlines())
        if n > MAX_LINES:
            found.append(f"{layering._shown(path)}: {n} lines")
    return found


def test_no_module_of_the_library_is_over_700_lines():
    assert too_long() == []


def test_a_long_module_is_named_with_its_length(tmp_path):
    long, short = tmp_path / "long.py", tmp_path / "short.py"
    long.write_text("x = 1\n" * (MAX_LINES + 1))
    short.write_text("x = 1\n" * MAX_LINES)
    assert too_long([long, short]) == [f"{long}: {MAX_LINES + 1} lines"]
