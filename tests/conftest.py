"""Fixtures shared by the closed-loop tests of the generated controller and of the flight package."""
import dataclasses

import pytest

from codegen import units
from host.cli.units import PAPER000_PARAMS
from host.control.nn_controller import default_package_config, load_artifact
from host.sim.scenarios import package_units
from tools.package import EvidencePlan, build_package


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


@pytest.fixture(scope="session")
def flight_package(tmp_path_factory):
    """A flight package as `staregen generate` writes it: the Fig. 2 controller flying the stand-in network
    and paper 000's tanh law (docs/tanh_paper000.toml) at 0.1 s (small evidence plan: its tests are others')."""
    cfg = dataclasses.replace(default_package_config(), units=("controller", "tanh"))
    network = load_artifact(None)
    bound = package_units(cfg, network, {"tanh": units.get("tanh").load_params(PAPER000_PARAMS)})
    plan = EvidencePlan(gate_vectors=200, gate_sequences=1, sequence_steps=20, selftest_vectors=16, cycles_per_class=1)
    out = tmp_path_factory.mktemp("flight_package") / "stare"
    build_package(out, cfg.name, bound, cfg.to_mapping(), {"network": {"sha256": network.sha256}}, plan,
                  log=lambda _line: None)
    return out
