"""skelcd.load and the Model: what `skelcd info --json` and `skelcd export --frame K` say of the
same bundled models."""

import numpy as np
import pytest

import skelcd
from helpers import MODELS, cli_json, load_arguments, run_cli


@pytest.fixture(scope="module")
def models():
    """Each bundled model loaded once for the module."""
    return {}


def loaded(models, name):
    if name not in models:
        path, load = MODELS[name]
        models[name] = skelcd.load(path, **load)
    return models[name]


@pytest.mark.parametrize("name", sorted(MODELS))
def test_info_equals_cli_info_json(models, name):
    path, load = MODELS[name]
    model = loaded(models, name)
    info = model.info()
    assert info == cli_json("info", path, *load_arguments(load))
    assert model.clips == [c["name"] for c in info["clips"]]
    assert model.triangles.shape == (info["triangles"], 3) and model.triangles.dtype == np.int32
    assert model.rest_positions.shape == (info["vertices"], 3) and model.rest_positions.dtype == np.float64
    assert model.triangles.min() >= 0 and model.triangles.max() < info["vertices"]
    assert model.argument == path


def read_obj(path):
    """(#V x 3 positions, #F x 3 zero-based triangles) of an OBJ file assimp wrote."""
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            fields = line.split()
            if fields and fields[0] == "v":
                vertices.append([float(x) for x in fields[1:4]])
            elif fields and fields[0] == "f":
                faces.append([int(corner.split("/")[0]) - 1 for corner in fields[1:4]])
    return np.array(vertices), np.array(faces)


@pytest.mark.parametrize("name, clip, sample", [
    ("CesiumMan", None, 17), ("Fox", "Walk", 5), ("panda", None, 45), ("funnel", None, 1),
])
def test_positions_equal_cli_export(models, name, clip, sample, tmp_path):
    """The posed corners of every triangle equal the OBJ `skelcd export --frame K` writes (which
    merges equal positions, so triangles are compared corner by corner) to its 9 printed digits."""
    path, load = MODELS[name]
    model = loaded(models, name)
    out = tmp_path / "posed.obj"
    run_cli("export", path, *load_arguments(load), *(["--clip", clip] if clip else []),
            "--frame", sample, "-o", out)
    obj_vertices, obj_faces = read_obj(out)
    positions = model.positions(sample, clip=clip)
    assert positions.shape == model.rest_positions.shape and positions.dtype == np.float64
    assert len(obj_faces) == len(model.triangles)
    scale = np.abs(positions).max()
    np.testing.assert_allclose(positions[model.triangles], obj_vertices[obj_faces], rtol=0, atol=1e-6 * scale)
    assert not np.allclose(positions, model.rest_positions) or sample == 0


def test_samples_and_times_follow_the_clip(models):
    model = loaded(models, "Fox")
    info = model.info()
    walk = next(c for c in info["clips"] if c["name"] == "Walk")
    n = model.num_samples("Walk")
    times = model.sample_times("Walk")
    assert len(times) == n and times[0] == 0
    assert times[-1] == pytest.approx(walk["duration_s"], rel=1e-6)
    assert model.num_samples("Walk", fps=60) > n
    assert model.num_samples() == model.num_samples(model.clips[0])
