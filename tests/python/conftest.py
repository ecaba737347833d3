"""Fixtures of the Python module's tests: the repository as working directory, so models are named
by the relative paths the CLI is given and logs and reports name them alike."""

import pytest

from helpers import ROOT


@pytest.fixture(autouse=True)
def in_repository(monkeypatch):
    monkeypatch.chdir(ROOT)
