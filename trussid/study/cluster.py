"""Studies on a batch system (SLURM, PBS, SGE, LSF, HTCondor, OAR): workers as batch jobs.

`dask-jobqueue <https://jobqueue.dask.org>`_ (``pip install trussid[cluster]``) submits the
Dask workers as batch jobs and runs their scheduler in the process that runs the study.
A cluster file (TOML) describes the jobs; ``trussid study SPEC --out DIR --cluster FILE``
reads it::

    [cluster]
    kind = "slurm"              # slurm | pbs | sge | lsf | htcondor | oar
    jobs = 2                    # batch jobs to submit
    cores = 32                  # per job; one worker process per core (processes = cores)
    memory = "64GB"             # per job
    walltime = "02:00:00"
    queue = "compute"
    account = "myproject"
    # any other keyword of dask_jobqueue.<Kind>Cluster: job_extra_directives = ["--exclusive"],
    # job_script_prologue = ["module load python"], interface = "ib0", ...

The workers run with one thread each and the environment of
:data:`trussid.study.engine.WORKER_ENV` / :data:`~trussid.study.engine.WORKER_CONFIG`
(exported at the top of the job script), as the local workers do. The cluster file does not
enter the spec hash: where a study runs never changes its results.
"""

from __future__ import annotations

import contextlib
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import dask
from distributed import Client

from trussid.study.engine import WORKER_CONFIG, WORKER_ENV
from trussid.study.spec import StudyError

#: ``kind`` -> the dask_jobqueue class.
KINDS = {"slurm": "SLURMCluster", "pbs": "PBSCluster", "sge": "SGECluster", "lsf": "LSFCluster",
         "htcondor": "HTCondorCluster", "oar": "OARCluster"}


@dataclass(frozen=True)
class ClusterConfig:
    """A batch-system cluster: its kind, the jobs to submit, the dask-jobqueue keywords.

    Attributes
    ----------
    kind : str
        A key of :data:`KINDS`.
    jobs : int
        Batch jobs to submit (``cluster.scale(jobs=...)``).
    options : dict
        Keywords of ``dask_jobqueue.<Kind>Cluster`` (cores, memory, walltime, queue, ...).
    source : str
        Where the configuration came from (for messages).
    """

    kind: str
    jobs: int
    options: dict = field(default_factory=dict)
    source: str = "cluster"


def worker_exports() -> list[str]:
    """Shell lines exporting the study workers' environment (job script prologue)."""
    env = dict(WORKER_ENV)
    for key, value in WORKER_CONFIG.items():
        # Dask reads DASK_A__B_C as the setting a.b-c (values parsed as Python literals)
        env["DASK_" + key.upper().replace(".", "__").replace("-", "_")] = repr(value)
    return [f"export {k}={v}" for k, v in env.items()]


def cluster_config_from_dict(d: dict, where: str = "cluster") -> ClusterConfig:
    """Read the ``[cluster]`` table (module docstring); errors name the item."""
    if not isinstance(d, dict) or set(d) != {"cluster"}:
        extra = sorted(set(d) - {"cluster"}) if isinstance(d, dict) else []
        raise StudyError(f"{where}: " + (f"unknown section [{extra[0]}] (a cluster file has only [cluster])"
                                          if extra else "a cluster file needs a [cluster] table"))
    c = dict(d["cluster"])
    kind = c.pop("kind", None)
    if kind not in KINDS:
        raise StudyError(f"{where}: [cluster] kind must be one of {', '.join(KINDS)}, got {kind!r}")
    jobs = c.pop("jobs", 1)
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise StudyError(f"{where}: [cluster] jobs must be a positive integer, got {jobs!r}")
    cores = c.get("cores")
    if isinstance(cores, bool) or not isinstance(cores, int) or cores < 1:
        raise StudyError(f"{where}: [cluster] cores (per job) must be a positive integer, got {cores!r}")
    if "memory" not in c:
        raise StudyError(f"{where}: [cluster] needs memory (per job, e.g. \"64GB\")")
    return ClusterConfig(kind=kind, jobs=jobs, options=c, source=where)


def load_cluster_config(path) -> ClusterConfig:
    """Read a cluster file (TOML, :func:`cluster_config_from_dict`)."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            raw = tomllib.load(fh)
    except FileNotFoundError:
        raise StudyError(f"{path}: no such cluster file") from None
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{path}: not valid TOML: {exc}") from None
    return cluster_config_from_dict(raw, where=str(path))


def jobqueue_cluster(cfg: ClusterConfig):
    """The dask-jobqueue cluster of ``cfg``, not yet scaled (no job submitted).

    Its scheduler runs in this process. Every worker process has one thread
    (``processes = cores`` unless given) and the study workers' environment, exported at
    the top of the job script before any line of the user's ``job_script_prologue``.
    """
    try:
        import dask_jobqueue  # optional dependency: the cluster extra
    except ImportError:
        raise StudyError(f"{cfg.source}: a batch-system cluster needs dask-jobqueue "
                         "(pip install 'trussid[cluster]')") from None
    cls = getattr(dask_jobqueue, KINDS[cfg.kind])
    opts = dict(cfg.options)
    opts.setdefault("processes", opts["cores"])
    opts["job_script_prologue"] = worker_exports() + list(opts.get("job_script_prologue") or [])
    try:
        # the scheduler runs here: it gets the study's Dask settings too (timers)
        with dask.config.set(WORKER_CONFIG):
            return cls(**opts)
    except (TypeError, ValueError) as exc:  # an unknown keyword, a malformed memory size...
        # dask-jobqueue's first line names the keyword; the rest repeats every keyword
        raise StudyError(f"{cfg.source}: [cluster]: {str(exc).strip().splitlines()[0]}") from None


@contextlib.contextmanager
def jobqueue_client(cfg: ClusterConfig):
    """A Client of the cluster of ``cfg`` with its jobs submitted; cancels them on exit."""
    cluster = jobqueue_cluster(cfg)
    try:
        cluster.scale(jobs=cfg.jobs)
        with Client(cluster) as client:
            yield client
    finally:
        cluster.close()


__all__ = ["ClusterConfig", "KINDS", "cluster_config_from_dict", "load_cluster_config", "jobqueue_cluster",
           "jobqueue_client", "worker_exports"]
