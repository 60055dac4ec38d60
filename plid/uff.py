"""Universal File Format (UFF/UNV) lab files through ``pyuff``: what LMS / Simcenter Test.Lab,
m+p, Brüel & Kjær and most modal-test software export and import.

Data sets handled
-----------------
58, function type 1 (time response)
    One record per channel: the sampled time history of an input or an output. Read into
    :class:`trussid.plid.data.IOData` (so ``trussid identify DATA.uff`` works) and
    written from it. A channel is an input if the record says so (ordinate data type 13,
    "excitation force", as modal-test software marks its force/drive channels), if its name
    starts with ``u`` (and an output if it starts with ``y``), or if ``inputs=`` /
    ``outputs=`` name it.
58, function type 4 (frequency response function)
    One record per output/input pair (response and reference DOF), read into and written
    from :class:`trussid.plid.frf.FRF`.
55 (data at nodes: mode shapes)
    One record per mode, real (normal modes, analysis type 2) or complex (analysis type 3),
    read into and written from :class:`trussid.plid.data.ModeShapes`.
15 (nodes) and 82 (trace lines)
    Test geometry: :class:`Geometry`.

Precision of the format: 58 values are written in double precision (12 significant digits,
``%20.11e``); the abscissa start and increment, and all 55 and 15 values, have 6 significant
digits (``%13.5e``). A sampling frequency read back from a 58 record is therefore rounded to
the nearest whole Hz when that whole number reproduces the 6-digit increment (1024 Hz is
written as an increment of 9.76563e-04 s and read back as 1024 Hz, not 1023.9996 Hz).

Every problem (a truncated file, a record of the wrong type, channels of different length or
sample rate, NaN in a channel, a file pyuff cannot parse) is a
:class:`trussid.plid.errors.DataError` naming the file, the record (counted from 1 in file
order) and the channel.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from trussid._util.files import atomic_path
from trussid.plid.data import IOData, ModeShapes, unknown_name
from trussid.plid.errors import DataError
from trussid.plid.frf import FRF
from trussid.plid.modal import pole_parameters

__all__ = ["Geometry", "UFFContents", "read_uff", "write_uff", "read_uff_data",
           "write_uff_data"]

#: 58 function types by number (the ones this module reads).
TIME_RESPONSE, FRF_TYPE = 1, 4
#: 58 ordinate "specific data type" of an excitation (drive / force) channel.
EXCITATION = 13
_FUNC_NAMES = {0: "general", 1: "time response", 2: "auto spectrum", 3: "cross spectrum",
               4: "frequency response function", 6: "coherence", 9: "PSD"}
_DIRS = {0: "", 1: "+X", -1: "-X", 2: "+Y", -2: "-Y", 3: "+Z", -3: "-Z", 4: "+RX", -4: "-RX",
         5: "+RY", -5: "-RY", 6: "+RZ", -6: "-RZ"}


@dataclass
class Geometry:
    """Test geometry: nodes (UFF 15) and trace lines (UFF 82).

    Attributes
    ----------
    node_ids : ndarray of int, shape (n,)
    xyz : ndarray, shape (n, 3)
        Node coordinates [m].
    lines : list of ndarray of int
        Each trace line as the node ids it visits (0 lifts the pen, as in UFF 82).
    """

    node_ids: np.ndarray
    xyz: np.ndarray
    lines: list = field(default_factory=list)


@dataclass
class UFFContents:
    """What a UFF file holds, by kind (None where the file has none)."""

    data: object = None       # IOData from 58 time responses
    frf: object = None        # (FRF, input_names, output_names) from 58 FRFs
    modes: object = None      # ModeShapes from 55
    geometry: Geometry | None = None
    skipped: list = field(default_factory=list)  # (record number, type) not read


# --------------------------------------------------------------------------- reading


def _pyuff():
    import pyuff  # imported here: a few hundred ms, needed only for UFF files

    return pyuff


def _records(path: Path) -> list[dict]:
    """Every data set of ``path`` as pyuff returns it, each checked to be complete.

    pyuff splits the file at its ``    -1`` delimiter lines and silently drops an unclosed
    last block, so the delimiters are counted here first: an odd count means the file ends
    inside a record (truncated).
    """
    source = str(path)
    raw = path.read_bytes()
    lines = raw.splitlines()
    # pyuff's own rule: '    -1' at the end of a line (trailing blanks allowed)
    delims = [i for i, ln in enumerate(lines) if ln.rstrip(b" \r").endswith(b"    -1")]
    if not delims:
        raise DataError(f"{source}: not a UFF file (no '    -1' data-set delimiter)")
    if len(delims) % 2:
        k = len(delims) // 2 + 1
        start = delims[-1]
        kind = lines[start + 1][:6].decode("latin-1").strip() if start + 1 < len(lines) else "?"
        raise DataError(f"{source}: record {k} (data set {kind or '?'}) is not closed: the file "
                        "ends inside it (truncated)")
    pyuff = _pyuff()
    try:
        uf = pyuff.UFF(str(path))
        types = [int(t) for t in uf.get_set_types()]
    except Exception as exc:  # pyuff raises bare Exception for every failure
        raise DataError(f"{source}: cannot read as UFF ({exc})") from None
    out = []
    for k, kind in enumerate(types):
        try:
            ds = uf.read_sets(k)
        except Exception as exc:  # pyuff raises bare Exception for every failure
            raise DataError(f"{source}: record {k + 1} (data set {kind}) cannot be read "
                            f"({exc})") from None
        ds = dict(ds)
        ds["_record"] = k + 1
        ds["_type"] = kind
        out.append(ds)
    return out


def _label(ds: dict, which: str = "rsp") -> str:
    ent = str(ds.get(f"{which}_ent_name", "NONE")).strip()
    node = int(ds.get(f"{which}_node", 0))
    d = _DIRS.get(int(ds.get(f"{which}_dir", 0)), str(ds.get(f"{which}_dir")))
    base = ent if ent and ent.upper() != "NONE" else "node"
    return f"{base}:{node}{d}"


def _channel_names(recs: list[dict]) -> list[str]:
    """id1 (the channel description) when every record has a distinct one, else the
    response entity, node and direction."""
    ids = [str(r.get("id1", "")).strip() for r in recs]
    if all(i and i.upper() != "NONE" for i in ids) and len(set(ids)) == len(ids):
        return ids
    return [_label(r) for r in recs]


def _snap_fs(dx: float) -> float:
    """1/dx, or the nearest whole number of Hz if it reproduces dx to the 6 significant
    digits a 58 header holds."""
    fs = 1.0 / dx
    whole = round(fs)
    if whole > 0 and abs(1.0 / whole - dx) <= 5e-6 * dx:
        return float(whole)
    return fs


def _check_values(ds: dict, name: str, source: str) -> np.ndarray:
    rec = ds["_record"]
    data = np.asarray(ds.get("data"))
    n_decl = int(ds.get("num_pts", data.size))
    if data.size != n_decl:
        raise DataError(f"{source}: record {rec} (channel '{name}') holds {data.size} values "
                        f"but declares {n_decl} (truncated or corrupt)")
    bad = ~np.isfinite(data)
    if bad.any():
        k = int(np.argmax(bad))
        raise DataError(f"{source}: record {rec} (channel '{name}') has a non-finite value "
                        f"({data[k]}) at sample {k}")
    return data


def _time_data(recs: list[dict], source: str, inputs, outputs):
    names = _channel_names(recs)
    values, dxs = [], []
    for ds, name in zip(recs, names):
        v = _check_values(ds, name, source)
        if np.iscomplexobj(v):
            raise DataError(f"{source}: record {ds['_record']} (channel '{name}') is a time "
                            "response with complex values")
        if int(ds.get("abscissa_spacing", 1)) == 1:
            dx = float(ds.get("abscissa_inc", 0.0))
        else:
            x = np.asarray(ds.get("x"), dtype=float)
            dx = float((x[-1] - x[0]) / (x.size - 1)) if x.size > 1 else 0.0
        if not dx > 0:
            raise DataError(f"{source}: record {ds['_record']} (channel '{name}') has no "
                            f"positive time increment (got {dx})")
        values.append(v.astype(float))
        dxs.append(dx)
    n0 = values[0].size
    for ds, name, v in zip(recs, names, values):
        if v.size != n0:
            raise DataError(f"{source}: record {ds['_record']} (channel '{name}') has "
                            f"{v.size} samples, record {recs[0]['_record']} (channel "
                            f"'{names[0]}') has {n0}")
    for ds, name, dx in zip(recs, names, dxs):
        if abs(dx - dxs[0]) > 5e-6 * dxs[0]:
            raise DataError(f"{source}: record {ds['_record']} (channel '{name}') is sampled "
                            f"every {dx:.6g} s, record {recs[0]['_record']} every {dxs[0]:.6g} s")
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise DataError(f"{source}: channel '{dup}' appears in more than one record")
    for lst in (inputs, outputs):
        for w in lst or []:
            if w not in names:
                raise unknown_name(w, names, source, "channel")
    is_exc = [int(ds.get("ordinate_spec_data_type", 0)) == EXCITATION for ds in recs]
    if inputs is None and outputs is None:
        in_idx = [k for k, n in enumerate(names) if is_exc[k] or n[:1] in "uU"]
        out_idx = [k for k, n in enumerate(names) if k not in in_idx and n[:1] in "yY"]
        rest = [k for k in range(len(names)) if k not in in_idx and k not in out_idx]
        if in_idx and rest:  # excitation channels marked: every other channel is a response
            out_idx, rest = sorted(out_idx + rest), []
        if rest:
            k = rest[0]
            raise DataError(f"{source}: cannot tell whether record {recs[k]['_record']} "
                            f"(channel '{names[k]}') is an input or an output: mark the "
                            "excitation channels (ordinate data type 13) or list them with "
                            "--inputs/--outputs")
    elif outputs is None:
        in_idx = [names.index(w) for w in inputs]
        out_idx = [k for k in range(len(names)) if k not in in_idx]
    elif inputs is None:
        out_idx = [names.index(w) for w in outputs]
        in_idx = [k for k in range(len(names)) if k not in out_idx]
    else:
        in_idx = [names.index(w) for w in inputs]
        out_idx = [names.index(w) for w in outputs]
    units = {}
    for k, ds in enumerate(recs):
        lab = str(ds.get("ordinate_axis_units_lab", "")).strip()
        if lab and lab.upper() != "NONE":
            units[names[k]] = lab
    t0 = float(recs[0].get("abscissa_min", 0.0) or 0.0)
    fs = _snap_fs(dxs[0])
    u = np.column_stack([values[k] for k in in_idx]) if in_idx else np.empty((n0, 0))
    y = np.column_stack([values[k] for k in out_idx]) if out_idx else np.empty((n0, 0))
    return IOData(u=u, y=y, fs=fs, input_names=[names[k] for k in in_idx],
                  output_names=[names[k] for k in out_idx], t=t0 + np.arange(n0) / fs,
                  units={n: units[n] for n in units
                         if n in [names[k] for k in in_idx + out_idx]})


def _frf_data(recs: list[dict], source: str):
    ins, outs, cells = [], [], {}
    f0 = None
    for ds in recs:
        name = f"{_label(ds, 'rsp')}/{_label(ds, 'ref')}"
        v = _check_values(ds, name, source).astype(complex)
        x = np.asarray(ds.get("x"), dtype=float)
        if f0 is None:
            f0 = x
        elif x.shape != f0.shape or not np.allclose(x, f0, rtol=1e-5, atol=1e-9):
            raise DataError(f"{source}: record {ds['_record']} (FRF '{name}') is on another "
                            f"frequency grid ({x.size} lines) than record {recs[0]['_record']} "
                            f"({f0.size} lines)")
        i_name, o_name = _label(ds, "ref"), _label(ds, "rsp")
        if i_name not in ins:
            ins.append(i_name)
        if o_name not in outs:
            outs.append(o_name)
        cells[(o_name, i_name)] = v
    H = np.zeros((f0.size, len(outs), len(ins)), dtype=complex)
    for (o, i), v in cells.items():
        H[:, outs.index(o), ins.index(i)] = v
    missing = [(o, i) for o in outs for i in ins if (o, i) not in cells]
    if missing:
        o, i = missing[0]
        raise DataError(f"{source}: no FRF record for output '{o}' and input '{i}'")
    return FRF(f=f0, H=H), ins, outs


def _mode_data(recs: list[dict], source: str):
    nodes = None
    freqs, damps, cols = [], [], []
    ncomp = 3
    for ds in recs:
        rec = ds["_record"]
        at = int(ds.get("analysis_type", 0))
        nn = np.asarray(ds.get("node_nums"), dtype=int)
        if nodes is None:
            nodes = nn
        elif nn.shape != nodes.shape or np.any(nn != nodes):
            raise DataError(f"{source}: record {rec} (mode shape) lists other nodes than "
                            f"record {recs[0]['_record']}")
        comps = [k for k in ("r1", "r2", "r3", "r4", "r5", "r6") if k in ds]
        ncomp = len(comps)
        shape = np.column_stack([np.asarray(ds[k]) for k in comps]).ravel()
        if not np.all(np.isfinite(shape)):
            k = int(np.argmax(~np.isfinite(shape)))
            raise DataError(f"{source}: record {rec} (mode shape) has a non-finite value at "
                            f"node {nodes[k // ncomp]} component {k % ncomp + 1}")
        if at == 2:
            freqs.append(float(ds["freq"]))
            damps.append(float(ds.get("modal_damp_vis", 0.0)))
        elif at in (3, 7):
            f, z, _ = pole_parameters([complex(ds["eig"])])
            freqs.append(float(f[0]))
            damps.append(float(z[0]))
        else:
            raise DataError(f"{source}: record {rec} (data set 55) has analysis type {at}, "
                            "not a mode shape (2 normal, 3 complex)")
        cols.append(shape)
    dofs = [(int(n), d + 1) for n in nodes for d in range(ncomp)]
    return ModeShapes(frequencies_hz=np.array(freqs), damping=np.array(damps),
                      shapes=np.column_stack(cols), dofs=dofs)


def read_uff(path) -> UFFContents:
    """Read a UFF file: time histories, FRFs, mode shapes and geometry, each checked.

    Parameters
    ----------
    path : path-like
        ``.uff`` or ``.unv`` file.

    Returns
    -------
    UFFContents
        ``data`` (IOData) from 58 time responses, ``frf`` (FRF, input names, output names)
        from 58 FRFs, ``modes`` (ModeShapes) from 55, ``geometry`` from 15 and 82;
        ``skipped`` lists (record, data set type) of records of other kinds.
    """
    return _read(Path(path), None, None)


def _read(path: Path, inputs, outputs) -> UFFContents:
    source = str(path)
    if not path.exists():
        raise DataError(f"no such UFF file: {path}")
    recs = _records(path)
    out = UFFContents()
    time_recs, frf_recs, mode_recs, node_recs, line_recs = [], [], [], [], []
    for ds in recs:
        kind = ds["_type"]
        if kind == 58:
            ft = int(ds.get("func_type", -1))
            if ft == TIME_RESPONSE:
                time_recs.append(ds)
            elif ft == FRF_TYPE:
                frf_recs.append(ds)
            else:
                out.skipped.append((ds["_record"], f"58 ({_FUNC_NAMES.get(ft, ft)})"))
        elif kind == 55:
            mode_recs.append(ds)
        elif kind == 15:
            node_recs.append(ds)
        elif kind == 82:
            line_recs.append(ds)
        else:
            out.skipped.append((ds["_record"], str(kind)))
    if time_recs:
        out.data = _time_data(time_recs, source, inputs, outputs)
    if frf_recs:
        out.frf = _frf_data(frf_recs, source)
    if mode_recs:
        out.modes = _mode_data(mode_recs, source)
    if node_recs:
        ids = np.concatenate([np.asarray(d["node_nums"], dtype=int) for d in node_recs])
        xyz = np.column_stack([np.concatenate([np.asarray(d[c], dtype=float)
                                               for d in node_recs]) for c in "xyz"])
        lines = [np.asarray(d["nodes"], dtype=int) for d in line_recs]
        out.geometry = Geometry(node_ids=ids, xyz=xyz, lines=lines)
    return out


def read_uff_data(path, inputs=None, outputs=None):
    """Time histories (UFF 58, function type 1) of ``path`` as IOData (not yet validated)."""
    path = Path(path)
    contents = _read(path, inputs, outputs)
    if contents.data is None:
        have = ", ".join(f"record {r}: data set {t}" for r, t in contents.skipped[:3])
        if contents.frf is not None:
            have = "frequency response functions (58, type 4)" + (f"; {have}" if have else "")
        if contents.modes is not None:
            have = "mode shapes (55)" + (f"; {have}" if have else "")
        raise DataError(f"{path}: no time histories (data set 58, function type 1) in the "
                        f"file; it holds {have or 'geometry only'}")
    return contents.data


# --------------------------------------------------------------------------- writing


def _58(name: str, values, x0: float, dx: float, func_type: int, *, rsp_node: int,
        ref_node: int = 0, rsp_dir: int = 0, ref_dir: int = 0, ordinate_type: int = 0,
        units: str = "NONE", abscissa=("Time", "s", 17), ref_name: str = "NONE") -> dict:
    values = np.asarray(values)
    return {
        "type": 58, "binary": 0, "func_type": func_type, "id1": name[:80], "id2": "trussid",
        "rsp_ent_name": name[:10].replace(" ", "_") or "NONE", "rsp_node": rsp_node,
        "rsp_dir": rsp_dir, "ref_ent_name": ref_name[:10].replace(" ", "_") or "NONE",
        "ref_node": ref_node, "ref_dir": ref_dir, "abscissa_spacing": 1,
        "abscissa_min": x0, "abscissa_inc": dx, "x": x0 + dx * np.arange(values.size),
        "data": values, "ordinate_spec_data_type": ordinate_type,
        "ordinate_axis_units_lab": units or "NONE",
        "abscissa_axis_lab": abscissa[0], "abscissa_axis_units_lab": abscissa[1],
        "abscissa_spec_data_type": abscissa[2], "orddenom_spec_data_type": 0,
    }


def _data_sets(data) -> list[dict]:
    t0 = float(data.t[0]) if data.t is not None else 0.0
    dx = 1.0 / data.fs
    sets = []
    for j, name in enumerate(data.input_names):
        sets.append(_58(name, data.u[:, j], t0, dx, TIME_RESPONSE, rsp_node=j + 1,
                        ordinate_type=EXCITATION, units=data.units.get(name, "NONE")))
    for i, name in enumerate(data.output_names):
        sets.append(_58(name, data.y[:, i], t0, dx, TIME_RESPONSE,
                        rsp_node=data.n_inputs + i + 1, units=data.units.get(name, "NONE")))
    return sets


def _frf_sets(frf, input_names, output_names) -> list[dict]:
    f = np.asarray(frf.f, dtype=float)
    df = (f[-1] - f[0]) / (f.size - 1) if f.size > 1 else 1.0
    if f.size > 1 and np.max(np.abs(np.diff(f) - df)) > 1e-9 * max(abs(df), 1.0):
        raise DataError("FRF to write: frequencies must be evenly spaced for UFF 58")
    m = len(input_names)
    sets = []
    for i, out in enumerate(output_names):
        for j, inp in enumerate(input_names):
            ds = _58(out, frf.H[:, i, j], float(f[0]), float(df), FRF_TYPE,
                     rsp_node=m + i + 1, ref_node=j + 1, ref_name=inp,
                     abscissa=("Frequency", "Hz", 18))
            ds["id1"] = f"{out}/{inp}"[:80]
            ds["rsp_ent_name"] = out[:10].replace(" ", "_")
            sets.append(ds)
    return sets


def _mode_sets(modes) -> list[dict]:
    if modes.dofs is None or len(modes.dofs) != modes.shapes.shape[0]:
        raise DataError("mode shapes to write: UFF 55 needs a (node, direction) for each of "
                        f"the {modes.shapes.shape[0]} rows of the shapes (ModeShapes.dofs)")
    nodes = sorted({n for n, _ in modes.dofs})
    complex_ = np.iscomplexobj(modes.shapes)
    sets = []
    for k in range(modes.shapes.shape[1]):
        comps = np.zeros((len(nodes), 3), dtype=complex if complex_ else float)
        for (node, d), v in zip(modes.dofs, modes.shapes[:, k]):
            if not 1 <= d <= 3:
                raise DataError(f"mode shapes to write: DOF ({node}, {d}): UFF 55 holds "
                                "translations 1-3 here")
            comps[nodes.index(node), d - 1] = v
        f, z = float(modes.frequencies_hz[k]), float(modes.damping[k])
        ds = {"type": 55, "id1": f"mode {k + 1}", "id2": "trussid", "model_type": 1,
              "data_ch": 2, "spec_data_type": 8, "load_case": 1, "mode_n": k + 1,
              "node_nums": np.array(nodes), "r1": comps[:, 0], "r2": comps[:, 1],
              "r3": comps[:, 2]}
        if complex_:
            wn = 2 * np.pi * f
            ds.update(analysis_type=3, eig=complex(-z * wn, wn * np.sqrt(max(1 - z * z, 0.0))),
                      modal_a=0j, modal_b=0j)
        else:
            ds.update(analysis_type=2, freq=f, modal_m=0.0, modal_damp_vis=z, modal_damp_his=0.0)
        sets.append(ds)
    return sets


def _geometry_sets(geometry: Geometry) -> list[dict]:
    ids = np.asarray(geometry.node_ids, dtype=int)
    xyz = np.asarray(geometry.xyz, dtype=float)
    one = np.ones(ids.size, dtype=int)
    sets = [{"type": 15, "node_nums": ids, "def_cs": 0 * one, "disp_cs": 0 * one,
             "color": 11 * one, "x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2]}]
    for k, line in enumerate(geometry.lines):
        sets.append({"type": 82, "trace_num": k + 1, "n_nodes": len(line), "color": 1,
                     "id": f"line {k + 1}", "nodes": np.asarray(line, dtype=int)})
    return sets


def write_uff(path, *, data=None, frf=None, modes=None, geometry=None) -> Path:
    """Write any of time histories, FRFs, mode shapes and geometry to one UFF file, atomically.

    Parameters
    ----------
    path : path-like
        ``.uff`` or ``.unv``.
    data : IOData, optional
        One 58 time-response record per channel (inputs marked as excitation, ordinate data
        type 13), double precision.
    frf : tuple (FRF, input_names, output_names), optional
        One 58 FRF record per output/input pair (an evenly spaced frequency grid).
    modes : ModeShapes, optional
        One 55 record per mode (complex shapes as complex modes, real ones as normal modes);
        DOFs must be translations (directions 1-3).
    geometry : Geometry, optional
        Nodes (15) and trace lines (82), written first.
    """
    path = Path(path)
    sets = []
    if geometry is not None:
        sets += _geometry_sets(geometry)
    if data is not None:
        sets += _data_sets(data)
    if frf is not None:
        sets += _frf_sets(*frf)
    if modes is not None:
        sets += _mode_sets(modes)
    if not sets:
        raise DataError(f"{path}: nothing to write")
    pyuff = _pyuff()
    with atomic_path(path) as tmp:
        pyuff.UFF(str(tmp)).write_sets(sets, mode="overwrite")
    return path


def write_uff_data(data, path) -> Path:
    """Write IOData as UFF 58 time responses (see :func:`write_uff`)."""
    return write_uff(path, data=data)
