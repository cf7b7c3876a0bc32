"""The calibration study (host.tune.calibrate): the residual against analytic values, the fit never
sees the network (two different networks give the same candidates and the same choice), the chosen
reading is the smallest residual, a zero noise scale is the reading without random errors, and the
CLI writes the chosen reading as a sealed scenario file."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from codegen.artifact import random_artifact
from host.cli import main
from host.core.constants import ARCSEC
from host.control.nn_controller import load_artifact
from host.control.pid import GainSets, TABLE1_GAINS
from host.sim import scenario_file
from host.sim.batched import simulate_pid_batch
from host.sim.simulator import SimConfig
from host.sim.targets import central_target, staring_targets
from host.tune import calibrate as cal
from host.tune.evaluate import ControllerSpec, table1_spec

READINGS = ("table6", "norm-star_norm-gyro_mnm-wheels")


def _plan(**kw) -> cal.CalibrationPlan:
    c = central_target()
    targets = tuple((t.name, t.lon, t.lat, i) for i, t in enumerate(staring_targets()[:2]))
    args = dict(targets=targets, central=(c.name, c.lon, c.lat, 0), readings=READINGS, duration=12.0,
                step_duration=45.0, response_targets=1, scales=(0.0, 1.0), scale_tolerance=0.2)
    args.update(kw)
    return cal.CalibrationPlan(**args)


def test_residual_is_the_rms_log_ratio():
    paper = {"central": {"J_A": 3.96e-4, "J_w": 4.23e-5}, "all": {"J_A": 3.96e-4, "J_w": 4.25e-5}}
    assert cal.residual(paper) == 0.0
    doubled = {w: {m: 2.0 * v for m, v in row.items()} for w, row in paper.items()}
    assert abs(cal.residual(doubled) - math.log(2.0)) < 1e-12
    one_off = {"central": {"J_A": 3.96e-4 * math.e, "J_w": 4.23e-5}, "all": dict(paper["all"])}
    assert abs(cal.residual(one_off) - 0.5) < 1e-12           # sqrt(1/4)


@pytest.fixture(scope="module")
def networks(tmp_path_factory):
    folder = tmp_path_factory.mktemp("nets")
    standin, other = folder / "standin.json", folder / "other.json"
    load_artifact(None).save(standin)
    random_artifact((12, 40, 3), seed=3).save(other)
    return str(standin), str(other)


def test_the_fit_does_not_see_the_network(networks):
    docs = [cal.calibrate(_plan(), table1_spec(), ControllerSpec("NN (float64)", "nn", (("artifact", n),)),
                          progress=False) for n in networks]
    assert docs[0]["candidates"] == docs[1]["candidates"] and docs[0]["chosen"] == docs[1]["chosen"]
    fits = [{k: v for k, v in d["scale_fit"].items() if k not in ("prediction", "nn_to_pid_ratio")} for d in docs]
    assert fits[0] == fits[1]                     # the noise-scale fit does not see the network either
    assert docs[0]["scale_fit"]["residual"] == min(t["residual"] for t in docs[0]["scale_fit"]["tried"])
    assert docs[0]["prediction"]["staring"]["NN (float64)"] != docs[1]["prediction"]["staring"]["NN (float64)"]
    residuals = {c["reading"]: c["residual"] for c in docs[0]["candidates"]}
    assert set(residuals) == set(READINGS)
    assert docs[0]["chosen"] == min(residuals, key=residuals.get)


def test_candidate_rows_are_the_pid_under_that_reading(networks):
    doc = cal.calibrate(_plan(readings=("norm-star_norm-gyro_mnm-wheels",), scales=(0.0,)), table1_spec(),
                        ControllerSpec("NN (float64)", "nn", (("artifact", networks[0]),)), progress=False)
    errors = scenario_file.from_reading("norm-star_norm-gyro_mnm-wheels").errors
    ts = staring_targets()[:2]
    direct = simulate_pid_batch([(t.lon, t.lat) for t in ts], GainSets.of(TABLE1_GAINS), (0,),
                                SimConfig(duration=12.0, errors=errors))
    assert abs(doc["candidates"][0]["pid"]["all"]["J_A"] - direct.J_A.mean()) <= 1e-12 * direct.J_A.mean()
    # the sweep scales the literal table6 reading; scale 0: no random error at all, the constants kept
    table6 = scenario_file.from_reading("table6").errors
    quiet = simulate_pid_batch([(t.lon, t.lat) for t in ts], GainSets.of(TABLE1_GAINS), (0,),
                               SimConfig(duration=12.0, errors=table6.scaled(0.0)))
    assert abs(doc["noise_sweep"]["J"]["PID (Table 1)"][0] - quiet.J().mean()) <= 1e-12 * quiet.J().mean()
    assert doc["noise_sweep"]["reading"] == "table6"
    assert np.all(np.asarray(table6.scaled(0.0).star.sigma) == 0) and table6.scaled(0.0).star.bias == table6.star.bias


def test_cli_writes_the_chosen_reading_as_a_sealed_scenario(networks, tmp_path, capsys):
    out = tmp_path / "cal"
    code = main(["calibrate", "--network", networks[0], "--readings", ",".join(READINGS), "--targets", "2",
                 "--duration", "12", "--response-targets", "1", "--scales", "0,1", "--no-progress", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    doc = json.loads((out / "calibration.json").read_text())
    chosen = scenario_file.load(out / "scenario.toml")
    assert chosen.reading == doc["chosen"] and chosen.sha256 == doc["chosen_scenario"]["sha256"]
    assert (out / "fig_ratio_vs_noise.png").stat().st_size > 1000
    assert doc["paper_nn_to_pid_ratio"] == pytest.approx(4.01e-4 / 6.09e-4)


def test_a_scaled_scenario_scales_the_random_errors_only():
    s = cal.scaled_scenario("table6", 0.3)
    base = scenario_file.from_reading("table6").errors
    assert s.reading == "table6-random-x0300"
    assert abs(s.errors.star.sigma[0] - 0.3 * ARCSEC) < 1e-20 and abs(s.errors.wheels.sigma[2] - 0.003) < 1e-18
    assert s.errors.star.bias == base.star.bias and s.errors.wheels.bias == base.wheels.bias
    assert scenario_file.from_values(s.describe()["values"]).sha256 == s.sha256     # a file can hold it
