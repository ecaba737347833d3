"""skelcd — self-collision detection for skeleton-driven animation, from Python.

The functions of the ``skelcd`` command line as calls on NumPy arrays (docs/python.md)::

    import skelcd
    model = skelcd.load("assets/characters/Fox.glb")
    result = skelcd.check(model, clip="Walk", log="fox-walk.h5")
    print(result.summary["ccd_vf"], len(result.contacts), result.contacts["toi_lower"][:5])

``load`` reads a rigged file, a URDF robot on a trajectory or an OBJ/PLY frame sequence;
``check`` runs ``skelcd check`` on one clip; ``read_log`` reads a log back. Tables are NumPy
structured arrays whose field names and types are the HDF5 log's columns (docs/log-format.md).
Bad input raises ``skelcd.InvalidInput`` (a ``ValueError``) or ``skelcd.IoError`` (an ``OSError``)
with the one-line message the command line prints. ``skelcd.batch`` checks many clips on a Dask
cluster.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from typing import Optional, Sequence, Union

import numpy as np

from . import _skelcd
from ._skelcd import InvalidInput, IoError, Model

__all__ = [
    "CONTACT_DTYPE",
    "CheckResult",
    "DCD_PAIR_DTYPE",
    "FRAME_DTYPE",
    "InvalidInput",
    "IoError",
    "LABEL_ALLOWED",
    "LABEL_BASELINE",
    "LABEL_NONE",
    "Model",
    "check",
    "load",
    "methods",
    "read_log",
]

__version__ = _skelcd.__version__

# Shown as skelcd.InvalidInput / skelcd.IoError in tracebacks, where users catch them.
InvalidInput.__module__ = __name__
IoError.__module__ = __name__
Model.__module__ = __name__

#: One row of /frames: a DCD sample (kind 0) or a CCD interval (kind 1); docs/log-format.md.
FRAME_DTYPE = np.dtype(
    [("sample", "<i4"), ("t0", "<f8"), ("t1", "<f8"), ("kind", "u1")]
    + [(name, "<i8") for name in _skelcd.counter_names()]
    + [(name, "<f8") for name in _skelcd.stage_names()]
    + [("total_us", "<f8")])

#: One row of /contacts: a CCD contact, VF (kind 0: vertex a, triangle b) or EE (kind 1: edges),
#: features in the file's numbering (part, index within the part, side of an edge or -1), and its
#: label: an event id (>= 0), LABEL_BASELINE, LABEL_ALLOWED or LABEL_NONE (docs/log-format.md).
CONTACT_DTYPE = np.dtype([
    ("frame", "<i4"), ("kind", "u1"),
    ("a_part", "<i4"), ("a_index", "<i4"), ("a_side", "i1"),
    ("b_part", "<i4"), ("b_index", "<i4"), ("b_side", "i1"),
    ("toi_lower", "<f8"), ("toi_upper", "<f8"), ("label", "<i4")])

#: One row of /dcd_pairs: triangles (a_part, a_index) and (b_part, b_index) intersect at `frame`;
#: `label` as in CONTACT_DTYPE.
DCD_PAIR_DTYPE = np.dtype([
    ("frame", "<i4"), ("a_part", "<i4"), ("a_index", "<i4"), ("b_part", "<i4"), ("b_index", "<i4"),
    ("label", "<i4")])

#: Labels of findings that belong to no event: the baseline had it, it is between allowed parts or
#: bones, or the log was written before labels existed (docs/events.md).
LABEL_BASELINE = -1
LABEL_ALLOWED = -2
LABEL_NONE = -3


@dataclass
class CheckResult:
    """What a check found, from ``check`` or read back from a log by ``read_log``.

    summary: the object ``skelcd check --json`` prints (model, clip, fps, first_sample,
        last_sample, method, accuracy, query, frames, intervals, dcd_pairs, ccd_vf, ccd_ee,
        frames_with_contacts, …, stages_ms, worst, log).
    rows: /frames, one row per DCD sample and CCD interval, in order (FRAME_DTYPE).
    contacts: /contacts (CONTACT_DTYPE). dcd_pairs: /dcd_pairs (DCD_PAIR_DTYPE).
    plan: what ``check`` ran (samples, intervals, rows, threads, serial_reason); None from a log.
    header: the log's root attributes (``read_log``; None from ``check``).
    verified: the log's rows all matched /checksums (``read_log``; None from ``check``).
    damage: what failed verification, one sentence each (``read_log``).
    events: the log's collision events (``read_log``), one dict each: id, first_sample,
        last_sample, t_first, t_last, t_first_contact (None when absent), parts (part ids), bones
        (names), peak_pairs, peak_sample, dcd_pairs, ccd_contacts, depth, merged_into (-1: none).
        None when the log holds no event data (written before events, or cut short); [] when the
        run had no event. From ``check``: its events, likewise. ``summary["events"]`` lists the
        events that did not merge into an older one, as ``check --json`` does.
    """

    summary: dict
    rows: np.ndarray
    contacts: np.ndarray
    dcd_pairs: np.ndarray
    plan: Optional[dict] = None
    header: Optional[dict] = None
    verified: Optional[bool] = None
    damage: list = field(default_factory=list)
    events: Optional[list] = None


def _table(columns: dict, dtype: np.dtype) -> np.ndarray:
    """A structured array of `dtype` from the extension's dict of equal-length columns."""
    rows = len(columns[dtype.names[0]])
    table = np.empty(rows, dtype=dtype)
    for name in dtype.names:
        table[name] = columns[name]
    return table


def _result(raw: dict) -> CheckResult:
    return CheckResult(
        summary=raw["summary"],
        rows=_table(raw["rows"], FRAME_DTYPE),
        contacts=_table(raw["contacts"], CONTACT_DTYPE),
        dcd_pairs=_table(raw["dcd_pairs"], DCD_PAIR_DTYPE),
        plan=raw.get("plan"),
        header=raw.get("header"),
        verified=raw.get("verified"),
        damage=list(raw.get("damage", [])),
        events=raw.get("events"),
    )


def load(path: Union[str, os.PathLike], trajectory: Union[str, os.PathLike, None] = None,
         srdf: Union[str, os.PathLike, None] = None,
         package_path: Sequence[Union[str, os.PathLike]] = ()) -> Model:
    """Loads a MODEL as ``skelcd info``/``check`` read it.

    path: a rigged file (glTF/GLB, FBX, Collada, .X, Ogre, …), a URDF robot, an OBJ/PLY frame
        sequence (a folder or a glob), or a generator spec such as ``"gen:rope?triangles=2000"``.
    trajectory, srdf, package_path: for a URDF robot, the joint trajectory CSV, the SRDF whose
        disabled pairs are not checked, and folders searched for ``package://`` meshes.
    Returns a Model: ``info()``, ``clips``, ``triangles`` (#F x 3 int32), ``rest_positions``
    (#V x 3 float64), ``positions(sample, clip=None, fps=0)``, ``num_samples(clip=None, fps=0)``.
    Raises IoError (missing or unreadable file) or InvalidInput (a file wrong as data).
    """
    return _skelcd.load(os.fspath(path), os.fspath(trajectory) if trajectory else "",
                        os.fspath(srdf) if srdf else "", [os.fspath(p) for p in package_path])


def _frames_text(frames) -> str:
    """`frames` as the CLI's --frames text: None, K, (A, B) with B None for the end, or "A:B"."""
    if frames is None:
        return ""
    if isinstance(frames, str):
        return frames
    if isinstance(frames, (int, np.integer)):
        return str(int(frames))
    first, last = frames
    return f"{'' if first is None else int(first)}:{'' if last is None else int(last)}"


def _call_text(name: str, arguments: dict) -> str:
    """How a call looks in Python, for the log's command_line attribute."""
    shown = ", ".join(f"{k}={v!r}" for k, v in arguments.items())
    return f"{os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else 'python3'}: skelcd.{name}({shown})"


def check(model_or_path: Union[Model, str, os.PathLike], clip: Optional[str] = None,
          fps: float = 0, frames=None, method: str = "auto", accuracy: str = "conservative",
          query: str = "both", min_separation: float = 0.0, threads: int = 1,
          log: Union[str, os.PathLike, None] = None, gamma: float = 0.05, seed: int = 1,
          segmentation: Union[str, os.PathLike, None] = None, baseline: str = "rest",
          baseline_slack: int = 2, allow=(), allow_adjacent_bones: bool = False,
          full_dcd: bool = False, reuse: bool = True, rigid_rows: bool = True) -> CheckResult:
    """Checks one clip for self-collision, as ``skelcd check MODEL -o LOG`` does.

    model_or_path: a Model from ``load``, or a path loaded with default options.
    clip: clip name (None: the first clip, the bind pose when there is none).
    fps: samples per second (0: the clip's frame rate, else 30; ``skelcd info`` shows it).
    frames: samples to check — None (all), K, (A, B) (both included; B None: to the end) or "A:B".
    method: one of ``methods()``; accuracy: conservative, exact or fast; query: dcd, ccd or both.
    min_separation: contact distance in model units. threads: workers (1: serial; 0: all cores);
        the findings do not depend on it.
    log: write the HDF5 log here (docs/log-format.md); None: no log.
    gamma, seed, segmentation: the radial-view options of rvbc/dynamic/auto (``--gamma``,
        ``--seed``, ``--segmentation SEG.h5``).
    baseline, baseline_slack, allow, allow_adjacent_bones: what findings are compared with and
        which pairs are allowed (``--baseline rest|sample:K|none|LOG.h5``, ``--baseline-slack``,
        ``--allow A:B`` per item of ``allow``, ``--allow-adjacent-bones``; docs/events.md).
    full_dcd: test every candidate at every sample (``--full-dcd``); by default, with both
        queries, each DCD updates the previous one from the interval's CCD contacts (the same
        pairs; docs/culling.md "Incremental DCD").
    reuse: False queries every CCD interval (``--no-reuse``); by default an interval that holds
        the last held pose gets that one's row (docs/check.md "Static intervals").
    rigid_rows: False tests the CCD pairs that skinning moves by one matrix too
        (``--no-rigid-rows``); by default kdop and auto's whole-mesh bvh skip them where the
        interval certifies their row (the same contacts; docs/culling.md "Rigid rows").
    The GIL is released while checking; Ctrl-C stops a serial check between rows.
    Raises InvalidInput (bad option, clip, frame range, method) or IoError (unreadable file, a
    log that cannot be written), with the command line's messages.
    """
    model = model_or_path if isinstance(model_or_path, Model) else load(model_or_path)
    arguments = {"clip": clip, "fps": fps, "frames": frames, "method": method,
                 "accuracy": accuracy, "query": query, "min_separation": min_separation,
                 "threads": threads, "log": None if log is None else os.fspath(log),
                 "baseline": baseline}
    if baseline_slack != 2:
        arguments["baseline_slack"] = baseline_slack
    if allow:
        arguments["allow"] = list(allow)
    if allow_adjacent_bones:
        arguments["allow_adjacent_bones"] = True
    if full_dcd:
        arguments["full_dcd"] = True
    if not reuse:
        arguments["reuse"] = False
    if not rigid_rows:
        arguments["rigid_rows"] = False
    if method in ("rvbc", "dynamic", "auto"):
        arguments.update(gamma=gamma, seed=seed, segmentation=segmentation)
    command_line = _call_text("check", {"model": model.argument,
                                        **{k: v for k, v in arguments.items() if v is not None}})
    raw = _skelcd.check(
        model, clip or "", float(fps), _frames_text(frames), method, accuracy, query,
        float(min_separation), int(threads), "" if log is None else os.fspath(log), float(gamma),
        int(seed), "" if segmentation is None else os.fspath(segmentation), command_line,
        os.fspath(baseline) if isinstance(baseline, os.PathLike) else str(baseline),
        int(baseline_slack), [str(a) for a in allow], bool(allow_adjacent_bones),
        bool(full_dcd), bool(reuse), bool(rigid_rows))
    return _result(raw)


def read_log(path: Union[str, os.PathLike]) -> CheckResult:
    """Reads a log written by ``skelcd check`` or ``check(log=…)``, complete or cut short.

    Rows are verified against the log's /checksums; tables are cut back to the last verified
    block when one fails, and ``damage`` says which (docs/log-format.md). ``summary`` is computed
    from the rows read (``skelcd inspect``'s numbers), ``header`` holds the root attributes.
    Raises IoError when the file is missing, not HDF5, not a skelcd log, or unreadable.
    """
    return _result(_skelcd.read_log(os.fspath(path)))


def methods() -> list:
    """Every method name ``check`` accepts, in ``skelcd bench`` order."""
    return list(_skelcd.method_names())
