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


# ----------------------------------------------------------------------------- batch sizes
def test_batches_aim_at_a_second_of_work_from_the_measured_cost_of_a_point():
    from trussid.study.engine import BatchSizer

    s = BatchSizer(first=20)
    assert s.size(remaining=10_000, threads=4) == 20  # nothing measured yet: the evaluator's hint
    s.observe(points=20, seconds=20 * 0.016)  # 16 ms a point
    assert s.size(remaining=100_000, threads=4) == 62  # floor(1 s / 16 ms)
    s.observe(points=20, seconds=20 * 0.004)  # the mean is now 10 ms a point
    assert s.size(remaining=100_000, threads=4) == 100


def test_batches_shrink_at_the_end_so_that_the_workers_finish_together():
    from trussid.study.engine import BatchSizer

    s = BatchSizer(first=1)
    s.observe(points=10, seconds=0.1)  # 10 ms a point
    assert s.size(remaining=400, threads=4) == 50  # remaining / (2 threads), below 1 s of work
    assert s.size(remaining=40, threads=4) == 15  # never under 0.15 s of work (per-task costs)
    assert s.size(remaining=7, threads=4) == 7
    slow = BatchSizer(first=1)
    slow.observe(points=1, seconds=3.0)  # a 3-s fit: one per task
    assert slow.size(remaining=30, threads=2) == 1


def test_a_fixed_chunk_overrides_the_measured_size(tmp_path):
    from trussid.study.engine import BatchSizer

    s = BatchSizer(first=20, fixed=7)
    s.observe(points=7, seconds=7 * 0.016)
    assert [s.size(r, 4) for r in (1000, 7, 3)] == [7, 7, 3]
    sizes = []
    run = run_study(small_spec(chunk=None), tmp_path / "s", workers=0, chunk=5, progress=lambda b: sizes.append(b.points))
    assert sizes == [5, 5, 2] and run.tasks == 3 and len(list((tmp_path / "s").glob("part-*.parquet"))) == 3


def test_the_run_reports_what_points_and_tasks_cost(tmp_path):
    run = run_study(small_spec(), tmp_path / "s", workers=0)
    df = read_study(tmp_path / "s")[1]
    assert run.tasks == 3 and (run.batch_min, run.batch_max) == (4, 4)
    assert run.eval_cpu_s == pytest.approx(df["cpu_seconds"].sum())
    assert run.eval_s == pytest.approx(df["seconds"].sum())
    assert run.task_cpu_s >= run.eval_cpu_s + run.context_cpu_s > 0
    assert run.peak_rss_mb > 50
    text = run.costs()
    assert "per point: evaluation" in text and "3 tasks of 4..4 points" in text


def test_a_stop_request_ends_the_run_after_the_batch_in_hand_and_a_rerun_completes(tmp_path):
    """The CLI's SIGINT/SIGTERM handler only sets a flag (an exception raised from a signal
    handler inside a finaliser is lost); the engine reads it after each saved batch."""
    spec, out = small_spec(), tmp_path / "s"
    saved = []
    with pytest.raises(KeyboardInterrupt):
        run_study(spec, out, workers=0, progress=lambda b: saved.append(b.points), stop=lambda: len(saved) >= 2)
    assert saved == [4, 4] and len(pd.read_parquet(out)) == 8
    again = run_study(spec, out, workers=0)
    assert (again.computed, again.already) == (4, 8)
