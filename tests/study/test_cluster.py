"""Studies on clusters the user runs: a ``dask scheduler`` and ``dask worker`` processes
started with Dask's command line (``--scheduler``), and batch jobs through dask-jobqueue
(``--cluster FILE``: here only the job script is checked, no batch system runs).

Acceptance 3 and 4 of issue 26. Every process started here listens on 127.0.0.1 only and
is killed in a ``finally`` with bounded waits.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import time

import pandas as pd
import pytest
import tomli_w

from trussid.study import read_study, run_study, spec_from_dict
from trussid.study.cluster import cluster_config_from_dict, jobqueue_cluster, load_cluster_config, worker_exports
from trussid.study.engine import WORKER_ENV
from trussid.study.spec import StudyError

WALL_STUDY = {"study": {"evaluate": "modes", "name": "lhs-120"}, "evaluate": {"n_modes": 16},
              "sample": {"method": "lhs", "n": 120, "seed": 26},
              "parameters": {f"wall{i}": {"low": 0.0006, "high": 0.0017} for i in range(6)}}


def table(out) -> pd.DataFrame:
    return read_study(out)[1].drop(columns=["seconds", "cpu_seconds", "worker"])


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _stop(procs, timeout=10.0):
    """Terminate the process groups, wait a bounded time, then kill what is left."""
    for p in procs:
        if p.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(p.pid, signal.SIGTERM)
    t_end = time.monotonic() + timeout
    for p in procs:
        try:
            p.wait(timeout=max(0.1, t_end - time.monotonic()))
        except subprocess.TimeoutExpired:
            pass
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, signal.SIGKILL)  # nanny and its worker process alike
        p.wait(timeout=10)


@contextlib.contextmanager
def dask_command_line_cluster(n_workers=2, timeout=120):
    """``dask scheduler`` + ``n_workers`` x ``dask worker --nthreads 1`` on loopback.

    Yields ``(address, worker_processes)``; each worker is its own process group (nanny and
    worker process), so that a test can kill one whole.
    """
    from distributed import Client

    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, **WORKER_ENV, "DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED": "False"}
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "start_new_session": True, "env": env}
    procs = [subprocess.Popen([sys.executable, "-m", "dask", "scheduler", "--host", "127.0.0.1", "--port",
                               str(port), "--no-dashboard"], **quiet)]
    try:
        for k in range(n_workers):
            procs.append(subprocess.Popen([sys.executable, "-m", "dask", "worker", address, "--host", "127.0.0.1",
                                           "--nthreads", "1", "--nworkers", "1", "--no-dashboard",
                                           "--name", f"w{k}", "--death-timeout", "60"], **quiet))
        with Client(address, timeout=timeout) as client:
            client.wait_for_workers(n_workers, timeout=timeout)
        yield address, procs[1:]
    finally:
        _stop(procs)


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    out = tmp_path_factory.mktemp("serial") / "s"
    run_study(spec_from_dict(WALL_STUDY), out, workers=0)
    return table(out)


def _cli(*args):
    return [sys.executable, "-m", "trussid", "study", *map(str, args)]


@pytest.mark.slow
def test_trussid_study_on_a_dask_command_line_cluster_gives_the_serial_table(tmp_path, serial):
    spec_file = tmp_path / "lhs.toml"
    spec_file.write_text(tomli_w.dumps(WALL_STUDY))
    with dask_command_line_cluster(2) as (address, _):
        res = subprocess.run(_cli(spec_file, "--out", tmp_path / "d", "--scheduler", address), capture_output=True,
                             text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert "computed 120 in this run (0 failed)" in res.stdout and "on 2 worker(s)" in res.stdout
    assert "per point: evaluation" in res.stdout and "per task:" in res.stdout  # the cost summary
    df = read_study(tmp_path / "d")[1]
    assert df["worker"].nunique() == 2
    pd.testing.assert_frame_equal(table(tmp_path / "d"), serial, check_exact=True)


@pytest.mark.slow
def test_a_dask_worker_killed_mid_study_the_study_completes_without_duplicates(tmp_path, serial):
    spec = spec_from_dict({**WALL_STUDY, "study": {**WALL_STUDY["study"], "chunk": 3}})
    spec_file = tmp_path / "lhs.toml"
    spec_file.write_text(tomli_w.dumps(spec.to_dict()))
    out = tmp_path / "d"
    with dask_command_line_cluster(2) as (address, workers):
        proc = subprocess.Popen(_cli(spec_file, "--out", out, "--scheduler", address, "--quiet"),
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            t0 = time.monotonic()
            while len(list(out.glob("part-*.parquet"))) < 2:
                assert proc.poll() is None, proc.communicate()
                assert time.monotonic() - t0 < 300
                time.sleep(0.02)
            os.killpg(workers[0].pid, signal.SIGKILL)  # the whole `dask worker`: nanny and worker
            stdout, stderr = proc.communicate(timeout=600)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(timeout=10)
    assert proc.returncode == 0, stderr
    assert "computed 120 in this run (0 failed)" in stdout
    df = read_study(out)[1]
    assert len(df) == 120 and df["point"].is_unique
    pd.testing.assert_frame_equal(table(out), serial, check_exact=True)


# ----------------------------------------------------------------------------- batch systems
SLURM = {"cluster": {"kind": "slurm", "jobs": 2, "cores": 32, "memory": "64GB", "walltime": "02:00:00",
                     "queue": "compute", "account": "myproject", "job_script_prologue": ["module load python"],
                     "scheduler_options": {"host": "127.0.0.1", "dashboard_address": "127.0.0.1:0"}}}


def test_a_slurm_cluster_file_gives_a_job_script_of_one_thread_workers_with_the_study_environment(tmp_path):
    path = tmp_path / "cluster.toml"
    path.write_text(tomli_w.dumps(SLURM))
    cluster = jobqueue_cluster(load_cluster_config(path))
    try:
        script = cluster.job_script()
        address = cluster.scheduler_address
    finally:
        cluster.close()
    lines = script.splitlines()
    assert address.startswith("tcp://127.0.0.1:")
    for directive in ("#SBATCH -p compute", "#SBATCH -A myproject", "#SBATCH --cpus-per-task=32",
                      "#SBATCH -t 02:00:00"):
        assert directive in lines
    # the study environment first, then the user's prologue, then the worker command
    exports = worker_exports()
    assert lines[lines.index(exports[0]):lines.index(exports[-1]) + 1] == exports
    assert lines.index(exports[-1]) < lines.index("module load python")
    assert "export MALLOC_MMAP_THRESHOLD_=33554432" in exports
    assert "export DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED=False" in exports
    command = lines[-1]
    assert command.startswith(sys.executable) and address in command
    assert "--nworkers 32" in command and "--nthreads 1" in command  # one process per core


def test_a_pbs_cluster_file_gives_a_pbs_job_script():
    cfg = cluster_config_from_dict({"cluster": {"kind": "pbs", "cores": 8, "memory": "16GB", "queue": "workq",
                                                "walltime": "01:00:00", "scheduler_options": {"host": "127.0.0.1", "dashboard_address": "127.0.0.1:0"}}})
    assert cfg.jobs == 1
    cluster = jobqueue_cluster(cfg)
    try:
        script = cluster.job_script()
    finally:
        cluster.close()
    assert "#PBS -q workq" in script and "#PBS -l walltime=01:00:00" in script
    command = script.splitlines()[-1]
    assert "--nworkers 8" in command and "--nthreads 1" in command


@pytest.mark.parametrize("cluster, message", [
    ({"kind": "k8s", "cores": 4, "memory": "8GB"}, r"kind must be one of slurm, pbs"),
    ({"kind": "slurm", "cores": 0, "memory": "8GB"}, r"cores \(per job\) must be a positive integer, got 0"),
    ({"kind": "slurm", "cores": 4}, r"needs memory"),
    ({"kind": "slurm", "cores": 4, "memory": "8GB", "jobs": -1}, r"jobs must be a positive integer, got -1"),
    ({"kind": "slurm", "cores": 4, "memory": "8GB", "queues": "x",
      "scheduler_options": {"host": "127.0.0.1", "dashboard_address": "127.0.0.1:0"}}, r"cluster\.toml: \[cluster\]: .*unexpected keyword argument 'queues'"),
])
def test_mistakes_in_a_cluster_file_name_the_item(tmp_path, cluster, message):
    path = tmp_path / "cluster.toml"
    path.write_text(tomli_w.dumps({"cluster": cluster}))
    with pytest.raises(StudyError, match=message):
        jobqueue_cluster(load_cluster_config(path))


def test_the_cli_refuses_a_bad_cluster_file_in_one_line_before_running(tmp_path):
    spec_file = tmp_path / "s.toml"
    spec_file.write_text(tomli_w.dumps(WALL_STUDY))
    (tmp_path / "c.toml").write_text('[cluster]\nkind = "slurm"\ncores = 4\n')
    res = subprocess.run(_cli(spec_file, "--out", tmp_path / "d", "--cluster", tmp_path / "c.toml"),
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "needs memory" in res.stderr and "Traceback" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "d").exists()


def test_the_exported_worker_environment_gives_dask_the_engines_settings():
    """Workers started by hand or by a job script read the study's Dask settings from the
    exported variables (issue 35: the timers), as local workers get them from the engine."""
    import dask

    from trussid.study.engine import WORKER_CONFIG

    env = dict(line.removeprefix("export ").split("=", 1) for line in worker_exports())
    # the shell strips one level of quotes: export X='1s' gives X=1s
    env = {k: v.strip("'") for k, v in env.items() if k.startswith("DASK_")}
    got = dask.config.collect_env(env)
    for key, value in WORKER_CONFIG.items():
        node = got
        for part in key.split("."):
            node = node[part] if part in node else node[part.replace("-", "_")]
        assert node == value, key
