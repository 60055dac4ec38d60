"""The study report: real figures from real tables (string-valued parameters included)."""

from __future__ import annotations

import matplotlib.image as mpimg
import pytest

from trussid.study import run_study, spec_from_dict, write_report


@pytest.mark.slow  # 6 N4SID fits and a figure: ~6 s
def test_an_identification_campaign_reports_error_against_noise_and_order(tmp_path):
    spec = spec_from_dict({
        "study": {"evaluate": "identify"},
        "evaluate": {"plant": "case_a", "n_samples": 1500, "n_validation": 800, "block_rows": [20]},
        "parameters": {"noise": ["60dB", "20dB"], "order": [20, 24, 28], "method": ["n4sid"]}})
    run_study(spec, tmp_path / "c", workers=0)
    md = write_report(tmp_path / "c").read_text()
    assert "6 ok, 0 failed" in md and "identification.png" in md
    img = mpimg.imread(tmp_path / "c" / "_report" / "identification.png")
    assert img.shape[1] > 800 and img[..., :3].std() > 0.05  # drawn, not blank
