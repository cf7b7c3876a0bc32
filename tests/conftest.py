"""Fixtures shared by the closed-loop tests of the generated controller."""
import pytest

from host.control.nn_controller import load_artifact


@pytest.fixture
def private_cache(tmp_path_factory, monkeypatch):
    """Builds of this module go to a cache of their own (no cross-talk with other runs)."""
    monkeypatch.setenv("STAREGEN_CACHE", str(tmp_path_factory.getbasetemp() / "cache"))


@pytest.fixture(scope="module")
def artifact_file(tmp_path_factory):
    """The stand-in network (fitted to the PID law) saved as an artifact file."""
    path = tmp_path_factory.mktemp("artifact") / "standin.json"
    load_artifact(None).save(path)
    return str(path)
