"""The FE benchmark's README table: one row per tool and case, the comparator's time as a
multiple of trussid's, failures shown as such, every row stamped with the commit."""

from tests.benchmarks_smoke.benchmark_module import benchmark_module


def _bench():
    return benchmark_module("bench_fem_vs_opensees")


def test_readme_table_rows_give_ratios_and_commits():
    b = _bench()
    ok = dict(status="ok", n_dof=100, cpu=1.0, peak_mb=50.0, load_before=3.0, setup=0.0)
    results = {"boom-x": {"trussid": {**ok, "assembly": 0.5, "modes": 1.5},
                          "opensees": {**ok, "assembly": 0.0, "modes": 8.0,
                                       "settings": {"system": "Mumps", "numberer": "RCM"}},
                          "scipy": {**ok, "status": "timeout after 1800 s", "peak_mb": 900.0}}}
    st = {"commit": "abc1234", "date_utc": "today", "machine": {"nproc": 2, "cpu": "cpu"}}
    table = b.readme_tables(results, st)["fem"]
    rows = {r[2]: r for r in table["rows"]}
    assert rows["trussid"][3] == "2.00" and rows["trussid"][6] == ""
    assert rows["OpenSeesPy (Mumps)"][6] == "4.0x"              # 8.0 s / 2.0 s
    assert rows["scipy eigsh shift-invert"][3] == "timeout after 1800 s"
    assert all(r[-1] == "abc1234" and len(r) == len(table["columns"]) for r in table["rows"])
