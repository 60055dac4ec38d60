"""The study engine in this process (``workers=0``): one row per point, resume computes only
what is missing, a failing point is a row with its reason, another study's output is refused.
The same engine on real Dask clusters: tests/study/test_engine_dask.py."""

from __future__ import annotations

import pandas as pd
import pytest

from trussid.study import StudyError, read_study, run_study, sample_points, spec_from_dict

R_OUT = 0.0067945  # the default testbed's tube outside radius [m]


def small_spec(chunk=4, **extra):
    d = {"study": {"evaluate": "modes", "chunk": chunk}, "evaluate": {"n_modes": 10, **extra},
         "parameters": {"wall0": {"low": 0.0006, "high": 0.0012, "num": 4},
                        "wall3": {"values": [0.001, 0.0014, 0.0016]}}}
    return spec_from_dict(d)


def table(out) -> pd.DataFrame:
    return read_study(out)[1].drop(columns=["seconds", "cpu_seconds", "worker"])


def test_every_point_is_one_row_with_its_parameters(tmp_path):
    spec = small_spec()
    run = run_study(spec, tmp_path / "s", workers=0)
    assert (run.total, run.computed, run.already, run.failed) == (12, 12, 0, 0)
    df = pd.read_parquet(tmp_path / "s")  # a plain Parquet dataset
    assert len(df) == 12 and df["point"].is_unique
    df = df.sort_values("point")
    names, pts = sample_points(spec)
    assert [tuple(r) for r in df[names].itertuples(index=False)] == pts
    assert (df["status"] == "ok").all() and (df["f7"] > 40).all()
    assert df["label7"].str.len().gt(0).all()


def test_a_rerun_computes_only_the_missing_points(tmp_path):
    spec = small_spec()
    out = tmp_path / "s"
    run_study(spec, out, workers=0)
    full = table(out)
    parts = sorted(out.glob("part-*.parquet"))
    lost = pd.read_parquet(parts[1])["point"].tolist() + pd.read_parquet(parts[2])["point"].tolist()
    parts[1].unlink(), parts[2].unlink()
    (out / ".part-0000099-half.parquet").write_bytes(b"PAR1 interrupted write")  # ignored
    again = run_study(spec, out, workers=0)
    assert again.computed == len(lost) == 8 and again.already == 4
    pd.testing.assert_frame_equal(table(out), full)
    assert run_study(spec, out, workers=0).computed == 0


def test_failing_points_are_rows_with_their_reasons(tmp_path):
    walls = [0.0008] * 20
    walls[5] = walls[13] = R_OUT * 1.1  # no tube: the wall is thicker than the radius
    spec = spec_from_dict({"study": {"evaluate": "modes", "chunk": 6}, "sample": {"method": "list"},
                           "evaluate": {"n_modes": 8, "labels": False},
                           "parameters": {"wall1": walls}})
    run = run_study(spec, tmp_path / "s", workers=0)
    assert (run.computed, run.failed) == (20, 2)
    df = read_study(tmp_path / "s")[1]
    bad = df[df["status"] == "failed"]
    assert bad["point"].tolist() == [5, 13]
    assert bad["error"].str.contains("strut 1 wall thickness").all()
    assert bad["f1"].isna().all()
    good = df[df["status"] == "ok"]
    assert len(good) == 18 and good["f8"].notna().all() and (good["error"] == "").all()


def test_another_spec_on_the_same_output_is_refused(tmp_path):
    out = tmp_path / "s"
    run_study(small_spec(), out, workers=0)
    with pytest.raises(StudyError, match=r"holds another study .*differ in options\.n_modes"):
        run_study(small_spec(n_modes=11), out, workers=0)
    # name and chunk size do not change results: the same study, nothing to do
    assert run_study(small_spec(chunk=5), out, workers=0).computed == 0


def test_a_directory_holding_other_files_is_refused(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(StudyError, match="is not a study output"):
        run_study(small_spec(), tmp_path, workers=0)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]
