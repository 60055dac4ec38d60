"""The results of a study on disk: a partitioned Parquet dataset plus the spec that made it.

Layout of an output directory ``DIR``::

    DIR/_study.json               spec (TOML layout as JSON), its hash, point count
    DIR/part-0000000-<id>.parquet one file per finished batch of points
    DIR/_report/                  plots and report.md (``trussid study DIR --report``)

``pandas.read_parquet(DIR)`` reads every part as one table, one row per point (Arrow's
dataset reader skips names starting with ``_`` or ``.``: the metadata, the report and any
half-written temporary file). A part is written under a ``.``-name and renamed when
complete, so an interrupted run leaves only whole batches; a rerun computes the points no
part holds.
"""

from __future__ import annotations

import json
import os
import uuid
from dataclasses import dataclass
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from trussid._util.files import atomic_path
from trussid.study.spec import StudyError, spec_from_dict, spec_hash

META = "_study.json"
#: Columns every row has besides its parameters and outputs.
STATUS_COLUMNS = [("status", pa.string()), ("error", pa.string()), ("seconds", pa.float64()),
                  ("cpu_seconds", pa.float64()), ("worker", pa.string())]


def _describe_difference(a: dict, b: dict, prefix: str = "") -> str:
    """The first key path where two spec identities differ."""
    for k in sorted(set(a) | set(b)):
        if k not in a or k not in b:
            return prefix + k
        if a[k] != b[k]:
            if isinstance(a[k], dict) and isinstance(b[k], dict):
                return _describe_difference(a[k], b[k], prefix + k + ".")
            return prefix + k
    return prefix.rstrip(".") or "spec"


@dataclass(frozen=True)
class StudyMeta:
    """The description a study output keeps in :data:`META`.

    Attributes
    ----------
    hash : str
        :func:`trussid.study.spec.spec_hash` of the study.
    points : int
        Points of the study.
    spec : dict
        The spec in its TOML layout (:meth:`trussid.study.spec.StudySpec.to_dict`).
    """

    hash: str
    points: int
    spec: dict

    @classmethod
    def read(cls, path: Path) -> "StudyMeta":
        """Parse ``path``; a :class:`StudyError` naming it (and the missing key) if it is
        not a study description."""
        try:
            raw = json.loads(path.read_text())
        except ValueError:
            raise StudyError(f"{path.parent}: {META} is not a study description") from None
        missing = [k for k in ("hash", "points", "spec") if not isinstance(raw, dict) or k not in raw]
        if missing:
            raise StudyError(f"{path.parent}: {META} is not a study description (no {missing[0]!r})")
        return cls(hash=str(raw["hash"]), points=int(raw["points"]), spec=raw["spec"])


class StudyStore:
    """An output directory bound to one study spec.

    Opening checks that ``out`` is empty, missing, or holds the *same* study (equal spec
    hash); anything else is refused with a :class:`StudyError` naming the directory and
    what differs.
    """

    def __init__(self, out, spec, schema: pa.Schema, n_points: int):
        self.out = Path(out)
        self.spec = spec
        self.schema = schema
        self.hash = spec_hash(spec)
        meta = self.out / META
        if meta.exists():
            old = StudyMeta.read(meta)
            old_hash = old.hash
            if old_hash != self.hash:
                try:
                    what = _describe_difference(spec_from_dict(old.spec).identity(), spec.identity())
                except StudyError:
                    what = "spec"
                raise StudyError(f"{self.out}: holds another study (spec hash {old_hash}, this spec "
                                 f"{self.hash}; they differ in {what}): use a new output directory")
        else:
            if self.out.exists() and (not self.out.is_dir() or any(self.out.iterdir())):
                raise StudyError(f"{self.out}: exists and is not a study output (no {META}); "
                                 "use a new or empty directory")
            self.out.mkdir(parents=True, exist_ok=True)
            with atomic_path(meta) as tmp:
                tmp.write_text(json.dumps({"hash": self.hash, "points": n_points,
                                           "spec": spec.to_dict()}, indent=1))

    def parts(self) -> list[Path]:
        return sorted(p for p in self.out.glob("part-*.parquet"))

    def done_points(self) -> set[int]:
        """Point numbers some finished part already holds."""
        done: set[int] = set()
        for p in self.parts():
            done.update(pq.read_table(p, columns=["point"]).column("point").to_pylist())
        return done

    def write_table(self, table: pa.Table) -> Path:
        """Write one batch of rows as a new part, atomically (temporary ``.``-name, rename)."""
        if table.schema != self.schema:
            table = table.cast(self.schema)
        first = pc.min(table.column("point")).as_py()
        path = self.out / f"part-{first:07d}-{uuid.uuid4().hex[:8]}.parquet"
        with atomic_path(path) as tmp:
            pq.write_table(table, tmp)
        return path


def read_study(out) -> tuple[StudyMeta, "pandas.DataFrame"]:  # noqa: F821
    """The stored description (spec in its TOML layout, hash, points) and the results of a
    study output, sorted by point."""
    import pandas as pd

    out = Path(out)
    meta = out / META
    if not meta.exists():
        raise StudyError(f"{out}: not a study output (no {META})")
    m = StudyMeta.read(meta)
    if not any(out.glob("part-*.parquet")):
        return m, pd.DataFrame()
    df = pd.read_parquet(out).sort_values("point").reset_index(drop=True)
    return m, df


__all__ = ["StudyStore", "StudyMeta", "read_study", "META", "STATUS_COLUMNS"]
