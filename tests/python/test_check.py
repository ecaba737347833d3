"""skelcd.check and skelcd.read_log against `skelcd check … -o LOG.h5 --json` on bundled clips:
the same findings, rows, summary and log."""

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
}

# Summary keys that are wall times (or the log's path); every other key must be equal.
TIMING_KEYS = {"ms_per_interval", "total_ms", "stages_ms", "log"}


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


def test_one_sample_is_dcd_only():
    result = skelcd.check("assets/characters/Fox.glb", clip="Walk", frames=4)
    assert list(result.rows["sample"]) == [4] and list(result.rows["kind"]) == [0]
    assert result.summary["intervals"] == 0 and len(result.contacts) == 0
