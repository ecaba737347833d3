"""skelcd.check and skelcd.read_log against `skelcd check … -o LOG.h5 --json` on bundled clips:
the same findings, rows, summary and log."""

import h5py
import numpy as np
import pytest

import skelcd
from helpers import MODELS, assert_logs_equal, assert_tables_equal, cli_json, load_arguments, table

# id → (model id, skelcd.check keyword arguments, the same as CLI options)
CASES = {
    "CesiumMan": ("CesiumMan", {}, []),
    "Fox-Walk": ("Fox", {"clip": "Walk"}, ["--clip", "Walk"]),
    "RiggedFigure-fps": ("RiggedFigure", {"fps": 8}, ["--fps", "8"]),
    "funnel-step": ("funnel", {}, []),
    "panda-reach": ("panda", {"frames": (36, 42)}, ["--frames", "36:42"]),
    "Fox-Run-kdop-ccd": ("Fox", {"clip": "Run", "method": "kdop", "query": "ccd"},
                         ["--clip", "Run", "--method", "kdop", "--query", "ccd"]),
    "Fox-Survey-dynamic": ("Fox", {"clip": "Survey", "method": "dynamic", "frames": "0:20"},
                           ["--clip", "Survey", "--method", "dynamic", "--frames", "0:20"]),
    # Events against another baseline, with allowances (docs/events.md).
    "CesiumMan-baseline-allow": ("CesiumMan",
                                 {"baseline": "sample:3", "frames": "0:8",
                                  "allow_adjacent_bones": True, "baseline_slack": 3},
                                 ["--baseline", "sample:3", "--frames", "0:8",
                                  "--allow-adjacent-bones", "--baseline-slack", "3"]),
}

# Summary keys that are wall times (or the log's path); every other key must be equal.
TIMING_KEYS = {"ms_per_interval", "total_ms", "stages_ms", "setup_ms", "log"}


def counts(summary):
    return {k: v for k, v in summary.items() if k not in TIMING_KEYS}


@pytest.fixture(scope="module", params=sorted(CASES))
def case(request, tmp_path_factory):
    """The check run both ways: (skelcd.check result, its log, the CLI's log, the CLI's JSON)."""
    model_id, python, cli = CASES[request.param]
    path, load = MODELS[model_id]
    folder = tmp_path_factory.mktemp(request.param)
    cli_log, py_log = folder / "cli.h5", folder / "python.h5"
    expected = cli_json("check", path, *load_arguments(load), *cli, "--threads", "1", "-o", cli_log)
    result = skelcd.check(skelcd.load(path, **load), log=py_log, **python)
    return result, py_log, cli_log, expected


def test_findings_equal_the_cli_log(case):
    result, _, cli_log, _ = case
    assert_tables_equal(result.contacts, table(cli_log, "contacts"), "contacts")
    assert_tables_equal(result.dcd_pairs, table(cli_log, "dcd_pairs"), "dcd_pairs")
    assert_tables_equal(result.rows, table(cli_log, "frames"), "frames")
    assert result.contacts.dtype == skelcd.CONTACT_DTYPE and result.rows.dtype == skelcd.FRAME_DTYPE


def test_summary_equals_cli_json(case):
    result, _, _, expected = case
    assert counts(result.summary) == counts(expected)
    assert result.summary["ccd_vf"] + result.summary["ccd_ee"] == len(result.contacts)
    assert result.summary["dcd_pairs"] == len(result.dcd_pairs)
    assert result.plan["rows"] == len(result.rows)


def test_python_log_equals_cli_log(case):
    _, py_log, cli_log, _ = case
    assert_logs_equal(py_log, cli_log)


def test_read_log_of_the_cli_log_equals_the_check(case):
    result, _, cli_log, expected = case
    read = skelcd.read_log(cli_log)
    assert read.verified and read.damage == []
    assert read.header["complete"] and read.header["planned_rows"] == len(read.rows)
    for name in ("contacts", "dcd_pairs", "rows"):
        ours, theirs = getattr(read, name), getattr(result, name)
        assert ours.dtype == theirs.dtype
        for column in ours.dtype.names:
            if not column.endswith("_us"):
                assert np.array_equal(ours[column], theirs[column]), f"{name}.{column}"
    # The summary of the rows read back (inspect's numbers) is the check's, but for the model's
    # name: a log records the MODEL argument as given.
    assert counts(read.summary) == counts(expected)
    assert read.summary["log"] == str(cli_log)


def test_threads_do_not_change_the_findings():
    serial = skelcd.check("assets/characters/Fox.glb", clip="Walk")
    parallel = skelcd.check("assets/characters/Fox.glb", clip="Walk", threads=2)
    assert parallel.plan["threads"] == 2
    for name in ("contacts", "dcd_pairs"):
        assert np.array_equal(getattr(serial, name), getattr(parallel, name))


def test_full_dcd_finds_the_same_pairs_with_more_tests():
    incremental = skelcd.check("assets/characters/RobotExpressive.glb", frames="0:20")
    full = skelcd.check("assets/characters/RobotExpressive.glb", frames="0:20", full_dcd=True)
    for name in ("contacts", "dcd_pairs"):
        assert np.array_equal(getattr(incremental, name), getattr(full, name))
    dcd = incremental.rows["kind"] == 0
    assert len(incremental.dcd_pairs) > 0
    # Each block of samples starts with a full DCD (docs/check.md, "Threads"), and the blocks
    # shrink towards the end of the clip: 7 of these 21 samples are full ones, where the update
    # saves nothing.
    assert incremental.rows["tt_tests"][dcd].sum() * 2 < full.rows["tt_tests"][dcd].sum()


def test_rigid_rows_and_reuse_switches_keep_the_findings(tmp_path):
    # kdop skips the CCD pairs of certified rigid rows (docs/culling.md "Rigid rows"): the same
    # contacts as with the switch off, from fewer candidate pairs; the log records the call.
    args = dict(frames="0:12", method="kdop", query="ccd")
    rows = skelcd.check("assets/characters/RobotExpressive.glb", **args)
    every = skelcd.check("assets/characters/RobotExpressive.glb", rigid_rows=False,
                         log=tmp_path / "every.h5", **args)
    assert np.array_equal(rows.contacts, every.contacts)
    assert rows.rows["candidate_pairs"].sum() * 4 < every.rows["candidate_pairs"].sum() * 3
    assert "rigid_rows=False" in skelcd.read_log(tmp_path / "every.h5").header["command_line"]
    # An interval that holds the pose of the last held one gets its row without a query (no stage
    # time) by default; reuse=False queries every one: the same rows' findings and counters
    # (docs/check.md "Static intervals"; Debian's unnamed_bones.mdl holds one pose).
    model = "/usr/share/assimp/models/MDL/MDL (HL1)/unnamed_bones.mdl"
    held = skelcd.check(model, frames="0:8", query="ccd", method="bvh")
    each = skelcd.check(model, frames="0:8", query="ccd", method="bvh", reuse=False)
    assert np.array_equal(held.contacts, each.contacts) and len(held.contacts) > 0
    counters = [n for n in skelcd.FRAME_DTYPE.names if n in ("candidate_pairs", "vf_tests",
                                                             "ee_tests", "bv_tests")]
    for name in counters:
        assert np.array_equal(held.rows[name], each.rows[name]), name
    stages = held.rows["traverse_us"] + held.rows["elementary_us"] + held.rows["refit_us"]
    queried = each.rows["traverse_us"] + each.rows["elementary_us"] + each.rows["refit_us"]
    assert (stages == 0).sum() >= 4 and (queried == 0).sum() == 0


def test_one_sample_is_dcd_only():
    result = skelcd.check("assets/characters/Fox.glb", clip="Walk", frames=4)
    assert list(result.rows["sample"]) == [4] and list(result.rows["kind"]) == [0]
    assert result.summary["intervals"] == 0 and len(result.contacts) == 0


def test_read_log_of_a_log_written_before_events():
    """The version-1 log of the C++ tests: unlabelled findings, no event data (None, not [])."""
    old = skelcd.read_log("tests/tools/data/log_before_events.hdf5")
    assert old.verified and old.damage == []
    assert old.events is None
    assert old.header["format_version"] == 1 and old.header["baseline"] == ""
    assert old.header["allow"] == [] and not old.header["allow_adjacent_bones"]
    assert old.dcd_pairs.dtype == skelcd.DCD_PAIR_DTYPE and len(old.dcd_pairs) == 1
    assert list(old.dcd_pairs["label"]) == [skelcd.LABEL_NONE]
    assert list(old.contacts["label"]) == [skelcd.LABEL_NONE] * 2
    assert list(old.rows["new_dcd_pairs"]) == [0, 0, 0] and old.rows["dcd_pairs"][0] == 1


def test_read_log_returns_the_events_and_the_labels(tmp_path):
    """A labelled log made with h5py (so without /checksums: read unverified): its events as dicts,
    the labels of its findings, the baseline attributes."""
    path = tmp_path / "events.h5"
    text = h5py.string_dtype()
    with h5py.File(path, "w") as f:
        f.attrs.update({"format": "skelcd-log", "format_version": 2, "clip": "Walk",
                        "baseline": "rest pose", "baseline_slack": 2, "allow_adjacent_bones": 1})
        f.attrs["allow"] = np.array(["body:cape", "Hips:Hips"], dtype=text)
        f["parts"] = np.array(["body", "cape"], dtype=text)
        f["frames"] = np.array([(0, 0.0, 0.0, 2, 1)], dtype=[
            ("sample", "<i4"), ("t0", "<f8"), ("t1", "<f8"), ("dcd_pairs", "<i8"),
            ("new_dcd_pairs", "<i8")])
        f["contacts"] = np.zeros(0, dtype=skelcd.CONTACT_DTYPE)
        f["dcd_pairs"] = np.array([(0, 0, 1, 1, 2, 0), (0, 0, 3, 1, 4, skelcd.LABEL_BASELINE)],
                                  dtype=skelcd.DCD_PAIR_DTYPE)
        f["events"] = np.array(
            [(0, 0, 4, 0.0, 0.125, np.nan, 1, 0, 3, 0, 0.25, -1),
             (1, 2, 2, 0.0625, 0.0625, 0.05, 0, -1, 0, 2, 0.0, 0)],
            dtype=[("id", "<i4"), ("first_sample", "<i4"), ("last_sample", "<i4"),
                   ("t_first", "<f8"), ("t_last", "<f8"), ("t_first_contact", "<f8"),
                   ("peak_pairs", "<i8"), ("peak_sample", "<i4"), ("dcd_pairs", "<i8"),
                   ("ccd_contacts", "<i8"), ("depth", "<f8"), ("merged_into", "<i4")])
        f["event_parts"] = np.array([(0, 0), (0, 1), (1, 1)],
                                    dtype=[("event", "<i4"), ("part", "<i4")])
        f["event_bones"] = np.array([(0, "Hips"), (0, "Spine 1"), (1, "Händ")],
                                    dtype=[("event", "<i4"), ("bone", text)])
    log = skelcd.read_log(path)
    assert not log.verified  # no /checksums
    assert log.header["baseline"] == "rest pose" and log.header["baseline_slack"] == 2
    assert log.header["allow"] == ["body:cape", "Hips:Hips"] and log.header["allow_adjacent_bones"]
    assert list(log.dcd_pairs["label"]) == [0, skelcd.LABEL_BASELINE]
    assert log.rows["new_dcd_pairs"][0] == 1 and log.rows["baseline_dcd_pairs"][0] == 0
    assert len(log.events) == 2
    first, second = log.events
    assert first == {"id": 0, "first_sample": 0, "last_sample": 4, "t_first": 0.0,
                     "t_last": 0.125, "t_first_contact": None, "parts": [0, 1],
                     "bones": ["Hips", "Spine 1"], "peak_pairs": 1, "peak_sample": 0,
                     "dcd_pairs": 3, "ccd_contacts": 0, "depth": 0.25, "merged_into": -1}
    assert second["t_first_contact"] == 0.05 and second["bones"] == ["Händ"]
    assert second["parts"] == [1] and second["merged_into"] == 0
