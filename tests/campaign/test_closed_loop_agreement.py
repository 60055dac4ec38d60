"""Issue 31, acceptance 6: the demo's closed-loop section and ``trussid closed-loop`` report
the same tracked pole and damping for every mode of the same controller on the same plant.

Before, the demo graded the plant it held in memory and the command the plant read back from
its file (``plant_true.npz``, equal to 1e-7); the tracking by eigenvector share flipped on that
difference (the 166 Hz mode: 179.7 Hz at 40.9 % in the report, 165.4 Hz at 7.21 % from the
command). Both now render the same typed summary with the same rule, which breaks near-ties
by the distance in the s-plane.
"""

import sys
from pathlib import Path

import control
import numpy as np

from trussid.campaign.loop_report import closed_loop_markdown, closed_loop_summary
from trussid.lqg.grading import plant_loop_settings, robustness
from trussid.plid.datafile import IOData, write_data
from trussid.plid.modelfile import load_model, save_model

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "lqg"))
from conftest import modal_structure  # noqa: E402  (the small structure of tests/lqg)


def _damping_rows(md: str) -> list:
    """``(f open, f closed, tracked, worst visible, visible controller poles)`` of the
    report's damping table, as printed."""
    lines = md.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("| f open [Hz]"))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("| "):
            break
        cells = [c.strip().strip("*") for c in line.strip("|").split("|")]
        rows.append((cells[0], cells[2], cells[3], cells[4], cells[5]))
    return rows


def test_the_demo_section_and_the_closed_loop_command_tabulate_the_same_poles(tmp_path):
    from trussid.cli import main

    plant = modal_structure()
    rng = np.random.default_rng(4)
    u = rng.normal(size=(3000, 3))
    y = control.forced_response(plant, U=u.T).outputs.T
    y = y + 0.01 * np.std(y) * rng.normal(size=y.shape)
    save_model(tmp_path / "plant.npz", plant)
    write_data(IOData(u, y, 1600.0, ["ch1", "ch2", "ch3"], ["acc1", "acc2", "acc3"]),
               tmp_path / "id.npz")
    assert main(["control", str(tmp_path / "plant.npz"), "--data", str(tmp_path / "id.npz"),
                 "--out", str(tmp_path / "c.npz"), "--no-baselines"]) == 0
    ctrl, meta = load_model(tmp_path / "c.npz")
    assert main(["closed-loop", str(tmp_path / "c.npz"), str(tmp_path / "plant.npz"),
                 "--out", str(tmp_path / "rep"), "--samples", "500"]) == 0
    command = _damping_rows((tmp_path / "rep" / "report.md").read_text())

    # the demo's path: the plant it holds in memory, the same grading and renderer
    settings = plant_loop_settings(plant, n_samples=500)
    study = robustness(ctrl, [("plant", plant)], {}, settings)
    demo = _damping_rows(closed_loop_markdown(closed_loop_summary(study)))
    assert len(demo) == len(command) == 4
    assert demo == command


def test_the_tracked_pole_does_not_depend_on_the_realisation():
    """A plant read back from a file differs from the one in memory by round-off (1e-7 in
    the demo's A): the same plant in another basis must track the same poles."""
    from trussid.lqg import design_lqg
    from trussid.lqg.evaluate import damping_table

    plant = modal_structure()
    rng = np.random.default_rng(11)
    u = rng.normal(size=(3000, 3))
    y = control.forced_response(plant, U=u.T).outputs.T
    des = design_lqg(plant, u, y + 0.01 * np.std(y) * rng.normal(size=y.shape))
    n = plant.nstates
    for T in (np.eye(n) + 1e-7 * rng.normal(size=(n, n)),            # round-off
              np.diag(rng.uniform(0.2, 5.0, n))):                      # another scaling
        Ti = np.linalg.inv(T)
        other = control.ss(Ti @ np.asarray(plant.A) @ T, Ti @ np.asarray(plant.B),
                           np.asarray(plant.C) @ T, plant.D, plant.dt,
                           inputs=list(plant.input_labels), outputs=list(plant.output_labels))
        a = damping_table(plant, des.controller, band=(0.0, 800.0))
        b = damping_table(other, des.controller, band=(0.0, 800.0))
        for ra, rb in zip(a.rows, b.rows):
            assert rb.frequency_closed == np.float64(ra.frequency_closed).round(6) or abs(
                rb.frequency_closed - ra.frequency_closed) < 1e-6 * ra.frequency_closed
            assert abs(rb.damping_tracked - ra.damping_tracked) < 1e-6
            assert abs(rb.damping_worst_visible - ra.damping_worst_visible) < 1e-6
