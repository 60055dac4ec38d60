"""Design studies and identification campaigns, from a laptop to a Dask cluster.

A study (:class:`StudySpec`, TOML or Python) names the parameters, how they are sampled,
and what is computed per point (:mod:`trussid.study.evaluators`: testbed modes with labels,
wall sensitivities, plant metrics, or a simulated record fitted and scored).
:func:`run_study` evaluates the points on Dask workers (:mod:`trussid.study.engine`) and
saves them as a partitioned Parquet dataset (:mod:`trussid.study.store`), resumably;
:func:`write_report` turns a finished study into plots and markdown. See docs/studies.md.
"""

from trussid.study.engine import StudyRun, evaluate_chunk, plan, run_study
from trussid.study.report import write_report
from trussid.study.errors import StudyError
from trussid.study.spec import Axis, StudySpec, load_spec, sample_points, spec_from_dict, spec_hash
from trussid.study.store import read_study

__all__ = ["StudySpec", "Axis", "StudyError", "load_spec", "spec_from_dict", "spec_hash", "sample_points",
           "run_study", "plan", "evaluate_chunk", "StudyRun", "read_study", "write_report"]
