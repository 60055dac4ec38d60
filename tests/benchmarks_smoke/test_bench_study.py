"""The study benchmark's guard (issue 35): CPU per design on the workers against the serial
loop's, the idle background taken out at the run's wall time and put back at an unloaded
machine's rate; a drift past the allowed overhead fails it."""

from tests.benchmarks_smoke.benchmark_module import benchmark_module


def _bench():
    return benchmark_module("bench_study")


def _results(worker_cpu_s: float) -> dict:
    serial = {"points": 1000, "wall_s": 10.0, "cpu_s": 10.0, "points_per_s": 100.0, "cpu_s_per_point": 0.010}
    # 1000 designs in 5 s on 2 workers; idle, the workers take 1 % of a core (both)
    run = {"workers": 2, "points": 1000, "wall_s": 5.0, "points_per_s": 200.0, "cpu_driver_s": 0.2,
           "cpu_workers_s": worker_cpu_s, "cpu_s_per_point": (worker_cpu_s + 0.2) / 1000,
           "idle_cpu_per_s_driver": 0.01, "idle_cpu_per_s_workers": 0.01}
    return {"wall_study": {"serial": serial, "workers2": run}}


def test_the_guard_passes_the_serial_cost_and_fails_a_drift_past_the_allowed_overhead():
    b = _bench()
    for worker_cpu_s, ok in ((10.3, True), (12.0, False), (20.0, False)):
        res = _results(worker_cpu_s)
        b.derive(res["wall_study"])
        (g,) = b.guards(res, quick=False)
        # less the background over the run (0.01 x 5 s), plus it at the unloaded rate (0.01 / 2)
        assert abs(g["value"] - ((worker_cpu_s - 0.05) / 1000 / 0.010 + 0.005)) < 1e-12
        assert g["bound"] == 1 + b.ALLOWED and g["ok"] is ok, (worker_cpu_s, g)


def test_the_quick_form_allows_more_for_a_small_study_on_a_busy_machine():
    b = _bench()
    res = _results(12.0)  # 1.2 x the serial loop's CPU per design
    b.derive(res["wall_study"])
    (g,) = b.guards(res, quick=True)
    assert g["ok"] and g["bound"] == 1 + b.ALLOWED_QUICK


def test_the_guard_takes_each_workers_own_loop_so_a_slow_serial_process_does_not_move_it():
    b = _bench()
    ratios = []
    for serial_cpu in (0.010, 0.016):  # the serial loop's process fast, then 1.6x slower
        res = _results(10.3)
        res["wall_study"]["serial"]["cpu_s_per_point"] = serial_cpu
        # the two workers' own bare loops: 9.5 and 10.5 ms, 600 and 400 designs done
        res["wall_study"]["workers2"]["own_serial_cpu_s"] = 600 * 0.0095 + 400 * 0.0105
        b.derive(res["wall_study"])
        (g,) = b.guards(res, quick=True)
        ratios.append(g["value"])
        assert g["against_serial_process"] == res["wall_study"]["workers2"]["worker_cpu_ratio_unloaded"]
    # (10.3 - 0.05) / (5.7 + 4.2) + the unloaded background, whatever the serial process read
    expected = (10.3 - 0.05) / 9.9 + 0.005
    assert abs(ratios[0] - expected) < 1e-12 and abs(ratios[1] - expected) < 1e-12


def test_repeated_fits_take_each_speed_up_against_the_same_repetitions_serial_loop(monkeypatch, tmp_path):
    """Five rotated repetitions; a repetition on a slow spell (every run 1.5x slower) leaves
    the medians where the others put them, and the pair of serial processes, which does the
    work twice over, counts it."""
    b = _bench()
    slow = iter([1.0, 1.0, 1.0, 1.0, 1.5] * 4)
    spell = {}

    def factor(k):
        if k not in spell:
            spell[k] = next(slow)
        return spell[k]

    calls = []

    def serial_loop(spec, worker_env):
        calls.append("serial")
        f = factor(len([c for c in calls if c == "serial"]))
        return {"points": 30, "wall_s": 12.0 * f, "cpu_s_per_point": 0.4 * f, "load_before": [1.0]}

    def serial_pair(spec):
        calls.append("pair")
        return {"points": 60, "wall_s": 13.0, "cpu_s_per_point": 0.43, "load_before": [1.0]}

    def engine_run(spec, workers, scratch, external=False, tag="", own=True):
        calls.append("ext" if external else "loc")
        wall = 6.5 if external else 6.0
        return {"points": 30, "wall_s": wall, "cpu_s_per_point": 0.41,
                "worker_threads": {"eval_s": 30 * 0.4}, "load_before": [1.0]}

    monkeypatch.setattr(b, "serial_loop", serial_loop)
    monkeypatch.setattr(b, "serial_pair", serial_pair)
    monkeypatch.setattr(b, "engine_run", engine_run)
    out = b.fits_repeated(None, tmp_path, 5)
    assert [r["order"][0] for r in out["rows"]] == ["serial", "workers2", "external2", "pair", "serial"]
    assert out["rows"][0]["workers2"]["speedup_wall"] == 12.0 / 6.0
    assert out["rows"][0]["pair"]["speedup_wall"] == 12.0 / 13.0 * 2
    m = out["summary"]
    assert m["workers2_speedup_wall"]["median"] == 2.0 and m["workers2_speedup_wall"]["max"] == 3.0
    assert m["external2_rate_vs_local"]["median"] == 6.0 / 6.5
    assert m["workers2_cpu_ratio"]["median"] == 1.0
