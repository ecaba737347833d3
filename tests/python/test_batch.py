"""skelcd.batch on a Dask LocalCluster of two single-threaded worker processes: the logs equal
those of `skelcd check` run clip by clip, named as the CLI's batch names them; a missing model is
a collected failure with the CLI's message; a second run skips every complete log."""

import json
import os
import shutil

import h5py
import pytest
from dask.distributed import Client, LocalCluster

from helpers import assert_logs_equal, cli_json, run_cli
from skelcd import batch

MODELS = [
    "assets/characters/CesiumMan.glb",
    "assets/characters/Fox.glb",
    "assets/characters/RiggedFigure.glb",
    "assets/characters/ninja/ninja.mesh",  # 20 clips, two of them refused: 18 checks
    "assets/characters/missing.glb",
]
CHECK = {"threads": 1}  # each worker checks one clip at a time, serially (the CLI: --threads 1)


@pytest.fixture(scope="module")
def client():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as c:
        yield c


@pytest.fixture(scope="module")
def cli_batch(tmp_path_factory):
    """`skelcd check MODELS… --all-clips -o DIR`: its log names and its failures (it exits 1)."""
    folder = tmp_path_factory.mktemp("cli-batch")
    done = run_cli("check", *MODELS, "--all-clips", "--threads", "1", "-o", folder, "--json",
                   expect_ok=False)
    report = json.loads(done.stdout)
    return sorted(os.listdir(folder)), report["failures"]


@pytest.fixture(scope="module")
def first_run(client, tmp_path_factory):
    out = tmp_path_factory.mktemp("dask-batch")
    result = batch.run(MODELS, out, all_clips=True, scheduler=client, progress=False, **CHECK)
    return out, result


def test_logs_are_named_as_the_cli_batch_names_them(first_run, cli_batch):
    out, result = first_run
    names, _ = cli_batch
    assert sorted(os.listdir(out)) == names
    assert len(result.done) == len(names) == 1 + 3 + 1 + 18
    assert sorted(os.path.basename(d["log"]) for d in result.done) == names


def test_logs_equal_skelcd_check_run_one_by_one(first_run, tmp_path):
    out, result = first_run
    for done in result.done:
        reference = tmp_path / os.path.basename(done["log"])
        expected = cli_json("check", done["model"], "--clip", done["clip"], "--threads", "1",
                            "-o", reference)
        assert_logs_equal(done["log"], reference)
        assert {k: done["summary"][k] for k in ("dcd_pairs", "ccd_vf", "ccd_ee", "frames", "intervals")} == \
               {k: expected[k] for k in ("dcd_pairs", "ccd_vf", "ccd_ee", "frames", "intervals")}


def test_a_missing_model_is_collected_with_the_cli_message(first_run, cli_batch):
    _, result = first_run
    _, cli_failures = cli_batch
    assert [(f["model"], f["error"]) for f in result.failures] == \
           [(f["model"], f["error"]) for f in cli_failures] == \
           [("assets/characters/missing.glb", "assets/characters/missing.glb: no such file")]
    assert not result.ok
    assert result.describe_failure(result.failures[0]) == "assets/characters/missing.glb: no such file"


def test_a_second_run_skips_complete_logs_and_redoes_the_others(first_run, client, tmp_path, capfd):
    out, first = first_run
    resumed = tmp_path / "resumed"
    shutil.copytree(out, resumed)
    # One log lost, one left incomplete by a killed run: only those two are checked again.
    lost, cut = sorted(os.listdir(resumed))[:2]
    os.remove(resumed / lost)
    with h5py.File(resumed / cut, "r+") as f:
        f.attrs["complete"] = 0
    result = batch.run(MODELS, resumed, all_clips=True, scheduler=client, progress=True, **CHECK)
    assert sorted(os.path.basename(d["log"]) for d in result.done) == [lost, cut]
    assert len(result.skipped) == len(first.done) - 2
    assert len(result.failures) == 1
    for name in (lost, cut):
        assert_logs_equal(resumed / name, out / name)
    progress = capfd.readouterr().err
    assert f"batch {len(first.done)}/{len(first.done)}" in progress and "skipped" in progress


def test_log_name_follows_the_cli():
    assert batch.log_name("assets/characters/Fox.glb", "Walk") == "Fox-Walk"
    assert batch.log_name("assets/cloth-funnel/frames/*.ply", "") == "frames"
    assert batch.log_name("assets/cloth-funnel/frames/", "227 228") == "frames-227_228"
    assert batch.log_name("gen:rope?triangles=200", "clip") == "gen_rope_triangles_200-clip"
