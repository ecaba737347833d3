"""Bad input through Python: the command line's one-line messages, as skelcd.IoError (an OSError)
and skelcd.InvalidInput (a ValueError)."""

import pytest

import skelcd
from helpers import cli_error

FOX = "assets/characters/Fox.glb"


def test_exception_classes_derive_from_the_standard_ones():
    assert issubclass(skelcd.InvalidInput, ValueError)
    assert issubclass(skelcd.IoError, OSError)
    assert skelcd.InvalidInput.__module__ == "skelcd" and skelcd.IoError.__module__ == "skelcd"


def test_a_missing_file_is_an_io_error_with_the_cli_message(tmp_path):
    missing = "assets/characters/missing.glb"
    with pytest.raises(skelcd.IoError) as load_error:
        skelcd.load(missing)
    assert str(load_error.value) == cli_error("info", missing)
    with pytest.raises(skelcd.IoError) as check_error:
        skelcd.check(missing, log=tmp_path / "never.h5")
    assert str(check_error.value) == cli_error("check", missing)
    assert not (tmp_path / "never.h5").exists()


def test_an_unknown_method_is_invalid_input_listing_the_methods(tmp_path):
    with pytest.raises(skelcd.InvalidInput) as error:
        skelcd.check(FOX, method="octree", log=tmp_path / "never.h5")
    assert str(error.value) == cli_error("check", FOX, "--method", "octree")
    assert skelcd.methods() == ["brute", "bvh", "kdop", "normal-cone", "dual-cone", "enhanced-dual-cone",
                                "auto", "rvbc", "dynamic"]
    for method in skelcd.methods():
        assert method in str(error.value)
    assert not (tmp_path / "never.h5").exists()


@pytest.mark.parametrize("python, cli", [
    ({"clip": "Swim"}, ["--clip", "Swim"]),
    ({"accuracy": "sloppy"}, ["--accuracy", "sloppy"]),
    ({"query": "xcd"}, ["--query", "xcd"]),
    ({"frames": "9:2"}, ["--frames", "9:2"]),
    ({"frames": (0, 500)}, ["--frames", "0:500"]),
])
def test_refused_options_have_the_cli_message(python, cli, tmp_path):
    with pytest.raises(skelcd.InvalidInput) as error:
        skelcd.check(FOX, log=tmp_path / "never.h5", **python)
    assert str(error.value) == cli_error("check", FOX, *cli)
    assert not (tmp_path / "never.h5").exists()


def test_a_sample_out_of_range_has_the_export_message(tmp_path):
    model = skelcd.load(FOX)
    with pytest.raises(skelcd.InvalidInput) as error:
        model.positions(99, clip="Walk")
    assert str(error.value) == cli_error("export", FOX, "--clip", "Walk", "--frame", 99, "-o", tmp_path / "x.obj")


def test_reading_what_is_not_a_log_is_an_io_error(tmp_path):
    with pytest.raises(skelcd.IoError) as error:
        skelcd.read_log(FOX)
    assert FOX in str(error.value)
    with pytest.raises(skelcd.IoError):
        skelcd.read_log(tmp_path / "missing.h5")
