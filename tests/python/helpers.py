"""What the Python module's tests share: the bundled models, running the `skelcd` CLI (the
reference every result is compared with), and comparing two logs table by table."""

import json
import os
import subprocess
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SKELCD = os.environ.get("SKELCD_EXE") or str(ROOT / "build" / "tools" / "skelcd")

PANDA = "assets/robots/example-robot-data/robots/panda_description/urdf/panda.urdf"
PANDA_LOAD = {
    "trajectory": "assets/trajectories/panda_reach.csv",
    "srdf": "assets/robots/example-robot-data/robots/panda_description/srdf/panda.srdf",
    "package_path": ["assets/robots"],
}

# id → (MODEL argument, skelcd.load keyword arguments)
MODELS = {
    "CesiumMan": ("assets/characters/CesiumMan.glb", {}),
    "Fox": ("assets/characters/Fox.glb", {}),
    "RiggedFigure": ("assets/characters/RiggedFigure.glb", {}),
    "RobotExpressive": ("assets/characters/RobotExpressive.glb", {}),
    "ninja": ("assets/characters/ninja/ninja.mesh", {}),
    "stormtrooper": ("assets/characters/stormtrooper/stormtrooper.dae", {}),
    "panda": (PANDA, PANDA_LOAD),
    "funnel": ("assets/cloth-funnel/frames", {}),
}


def load_arguments(load: dict) -> list:
    """skelcd.load's keyword arguments as CLI options."""
    args = []
    if load.get("trajectory"):
        args += ["--trajectory", load["trajectory"]]
    if load.get("srdf"):
        args += ["--srdf", load["srdf"]]
    for p in load.get("package_path", []):
        args += ["--package-path", p]
    return args


def run_cli(*args, expect_ok=True) -> subprocess.CompletedProcess:
    """Runs `skelcd ARGS…` in the repository; fails the test when its exit status is unexpected."""
    done = subprocess.run([SKELCD, *map(str, args)], cwd=ROOT, capture_output=True, text=True)
    if expect_ok:
        assert done.returncode == 0, f"skelcd {' '.join(map(str, args))}: {done.stderr}"
    else:
        assert done.returncode != 0, f"skelcd {' '.join(map(str, args))} succeeded"
    return done


def cli_json(*args) -> dict:
    return json.loads(run_cli(*args, "--json").stdout)


def cli_error(*args) -> str:
    """The one line a failing `skelcd ARGS…` prints, without its `skelcd: ` prefix."""
    line = run_cli(*args, expect_ok=False).stderr.strip().splitlines()[-1]
    assert line.startswith("skelcd: "), line
    return line[len("skelcd: "):]


def is_timing(name: str) -> bool:
    return name.endswith("_us")


# What differs between two runs of the same check: wall times, the CRCs of rows holding them,
# and when and how the run was started.
SKIPPED_ATTRIBUTES = {"command_line", "start_time"}
SKIPPED_COLUMNS = {"/checksums": {"frames_crc", "self_crc"}}


def log_contents(path) -> dict:
    """Every dataset (by column, timing columns left out) and attribute of an HDF5 log."""
    contents = {}
    with h5py.File(path, "r") as f:
        contents["attributes /"] = {k: v for k, v in f.attrs.items() if k not in SKIPPED_ATTRIBUTES}

        def visit(name, item):
            name = "/" + name
            contents["attributes " + name] = dict(item.attrs.items())
            if not isinstance(item, h5py.Dataset):
                return
            data = item[()]
            if data.dtype.names:
                for column in data.dtype.names:
                    if not is_timing(column) and column not in SKIPPED_COLUMNS.get(name, ()):
                        contents[f"{name}:{column}"] = data[column]
            else:
                contents[name] = data

        f.visititems(visit)
    return contents


def assert_logs_equal(a, b):
    """Logs `a` and `b` hold the same datasets and attributes, but for wall times (docs/log-format.md)."""
    ca, cb = log_contents(a), log_contents(b)
    assert sorted(ca) == sorted(cb), f"{a} and {b} hold different datasets"
    for key in ca:
        va, vb = ca[key], cb[key]
        if isinstance(va, dict):
            assert sorted(va) == sorted(vb), f"{key}: {a} vs {b}"
            for name in va:
                assert np.array_equal(np.asarray(va[name]), np.asarray(vb[name])), \
                    f"{key} {name}: {va[name]!r} in {a}, {vb[name]!r} in {b}"
        else:
            # NaN is a value in a log (/events:t_first_contact when there is none).
            same = np.array_equal(va, vb, equal_nan=va.dtype.kind == "f")
            assert va.dtype == vb.dtype and same, f"{key} differs between {a} and {b}"


def table(path, name) -> np.ndarray:
    with h5py.File(path, "r") as f:
        return f[name][()]


def assert_tables_equal(ours: np.ndarray, theirs: np.ndarray, what: str):
    """Same rows, column by column (ours: skelcd's arrays; theirs: h5py's), timings left out."""
    assert len(ours) == len(theirs), f"{what}: {len(ours)} rows, expected {len(theirs)}"
    assert set(ours.dtype.names) == set(theirs.dtype.names), what
    for column in ours.dtype.names:
        if not is_timing(column):
            assert ours[column].dtype.str == theirs[column].dtype.str, f"{what}: column {column} type"
            assert np.array_equal(ours[column], theirs[column]), f"{what}: column {column} differs"
