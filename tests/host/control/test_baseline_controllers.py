"""The fitted baselines flown in the closed loop: the baselines file gives back the very
coefficients, bad files are one-line errors, and the controllers fly with the noisy inputs."""
from __future__ import annotations

import json

import numpy as np
import pytest

from host.cli import main
from host.control.baseline_controllers import make_linear_controller, make_pdff_controller
from host.control.baselines import LinearLS, SaturatedLinear, baselines_document, load_baselines
from host.errors import HostError
from host.sim.metrics import staring_metrics
from host.sim.simulator import SimConfig, simulate
from host.sim.targets import central_target


def _laws():
    rng = np.random.default_rng(1)
    X = rng.uniform(-1, 1, (200, 12)) * np.array([0.1, 1.2, 0.05, 0.005, 0.015, 0.005] + [0.02] * 3 + [0.004] * 3)
    Y = -(X[:, 6:9] * 20.0 + X[:, 9:12] * 60.0) + rng.normal(0, 1e-3, (200, 3))
    return LinearLS.fit(X, Y), SaturatedLinear.fit(X, Y, 0.5)


@pytest.fixture()
def laws_file(tmp_path):
    linear, pdff = _laws()
    path = tmp_path / "network.baselines.json"
    path.write_text(json.dumps(baselines_document(linear, pdff, "ab" * 32)))
    return path


def test_the_file_gives_back_the_coefficients_bit_for_bit(laws_file):
    linear, pdff = _laws()
    l2, p2 = load_baselines(laws_file)
    assert np.array_equal(l2.coef, linear.coef) and np.array_equal(p2.coef, pdff.coef)
    assert p2.bound == pdff.bound and p2.n_fit == pdff.n_fit


@pytest.mark.parametrize("edit, message", [
    (lambda d: d.update(format="x"), "not a baselines file"),
    (lambda d: d["linear"].update(coef=[["0x1p+0"]]), r"linear.coef must be \(13, 3\)"),
    (lambda d: d["pdff"]["coef"][0].__setitem__(0, "nan"), "finite"),
    (lambda d: d["pdff"]["coef"][0].__setitem__(0, "one"), "hex floats"),
    (lambda d: d["pdff"].update(bound=-1), "pdff.bound"),
    (lambda d: d["pdff"].update(bound=True), "pdff.bound"),
    (lambda d: d["pdff"].update(n_fit=[1, 2]), "n_fit"),
    (lambda d: d.pop("linear"), "linear.coef"),
])
def test_bad_files_are_one_line_errors(laws_file, edit, message):
    doc = json.loads(laws_file.read_text())
    edit(doc)
    laws_file.write_text(json.dumps(doc))
    with pytest.raises(HostError, match=message) as exc:
        load_baselines(laws_file)
    assert "\n" not in str(exc.value)


def test_controllers_fly_the_laws_with_noisy_inputs(laws_file):
    tg = central_target()
    for make, law in ((make_pdff_controller, _laws()[1]), (make_linear_controller, _laws()[0])):
        c = make(torque_limit=1.0, control_period=0.1, baselines=str(laws_file))
        h = simulate(c, tg.lon, tg.lat, SimConfig(duration=12.0))
        m = staring_metrics(h.t, h.A_bd, h.omega_e, t_end=12.0)
        assert np.isfinite(m.J) and m.J < 1e-2
        # the command is the law on the controller's own (noisy) view, clipped at the wheel limit
        k = 30 * 5
        x = np.concatenate([h.omega_d[k], h.omegadot_d[k], h.A_bd_ctrl[k], h.omega_e_ctrl[k]]) / np.radians(1.0)
        want = np.clip(law.predict(x[None])[0], -1.0, 1.0)
        assert np.allclose(h.torque_cmd[k], want, rtol=1e-9, atol=1e-12)


def test_cli_options(laws_file, tmp_path, capsys):
    assert main(["simulate", "--controller", "pdff", "--duration", "12", "--baselines", str(laws_file),
                 "--out", str(tmp_path / "s")]) == 0
    assert (tmp_path / "s" / "metrics.json").is_file()
    capsys.readouterr()
    for argv, message in ((["--controller", "pdff"], "needs --baselines"),
                          (["--controller", "pid", "--baselines", str(laws_file)], "--baselines applies"),
                          (["--controller", "linear", "--baselines", str(tmp_path / "none.json")], "cannot read")):
        assert main(["simulate", "--duration", "12", *argv, "--out", str(tmp_path / "t")]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1
