"""The benchmark runner knows every script of benchmarks/: ``run.py --quick`` (in .ci/run) runs
each one in a small form, so none can rot unseen (issue 22: bench_plid.py had stopped
importing and nothing noticed)."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _run():
    spec = importlib.util.spec_from_file_location("bench_run", ROOT / "benchmarks" / "run.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_every_script_in_benchmarks_is_registered_with_a_quick_form():
    run = _run()
    assert run.unregistered() == []
    for name, (full, quick) in run.BENCHMARKS.items():
        assert full[0] == quick[0] and (ROOT / "benchmarks" / quick[0]).is_file(), name
    assert all((ROOT / "benchmarks" / f).is_file() for f in run.HELPERS)


def test_a_new_unregistered_script_is_found_and_stops_the_runner(tmp_path, monkeypatch, capsys):
    run = _run()
    for f in (ROOT / "benchmarks").glob("*.py"):
        (tmp_path / f.name).write_text("")
    (tmp_path / "bench_new.py").write_text("print('never run')\n")
    assert run.unregistered(tmp_path) == ["bench_new.py"]
    monkeypatch.setattr(run, "unregistered", lambda: ["bench_new.py"])
    monkeypatch.setattr(run, "run_one", lambda *a: (_ for _ in ()).throw(AssertionError("ran")))
    assert run.main(["--quick"]) == 2
    assert "bench_new.py in benchmarks/ is neither a benchmark nor a helper" in capsys.readouterr().err


def test_ci_runs_the_quick_form_of_all_of_them():
    assert ".venv/bin/python benchmarks/run.py --quick\n" in (ROOT / ".ci" / "run").read_text()
