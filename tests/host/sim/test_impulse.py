"""Impulse response (paper 001 Sec. 7.8, Fig. 15): the PID takes over during the 1 N·m impulse and
the network is back in command within 3 s of its end (measured: 1.9 s, of which 1 s is the dwell)."""
import json

import numpy as np
import pytest

from host.sim import impulse
from host.cli import main
from host.core.constants import DEG

NN_BACK_WITHIN_S = 3.0


pytestmark = pytest.mark.usefixtures("private_cache")


def test_impulse_torque_profile():
    assert impulse.impulse_torque(29.98).tolist() == [0, 0, 0]
    assert impulse.impulse_torque(30.0).tolist() == [1, 1, 1] == impulse.impulse_torque(30.48).tolist()
    assert impulse.impulse_torque(30.5).tolist() == [0, 0, 0]


@pytest.mark.parametrize("controller", ["nn", "nn-c"])
def test_pid_takes_over_and_hands_back(artifact_file, controller):
    r = impulse.run(controller, artifact_file, duration=45.0)
    h = r.history
    before = h.t < impulse.IMPULSE_START
    during = (h.t >= impulse.IMPULSE_START + 0.1) & (h.t < impulse.IMPULSE_START + impulse.IMPULSE_LENGTH)
    assert set(h.mode[before]) == {"nn"}                       # the network flew until the impulse
    assert set(h.mode[during]) == {"pid"}                      # the PID during the disturbance
    assert r.t_pid_first == pytest.approx(impulse.IMPULSE_START + 0.1)   # the first control instant that sees it
    assert r.peak_w_deg_s > 0.004                              # driven outside Table 2 (ω_e bound)
    end = impulse.IMPULSE_START + impulse.IMPULSE_LENGTH
    assert r.t_nn_back is not None and r.t_nn_back - end <= NN_BACK_WITHIN_S
    assert set(h.mode[h.t >= r.t_nn_back]) == {"nn"}           # and it stays in command
    assert np.max(np.abs(h.A_bd[h.t >= 40.0])) < 0.005 * DEG  # converged
    # bumpless: the command changes at the hand-back by less than 0.1 N·m (measured 0.048 N·m;
    # step-to-step changes of the y command right after it reach 0.17 N·m)
    k = int(np.searchsorted(h.t, r.t_nn_back - 1e-9))
    assert np.max(np.abs(h.torque_cmd[k] - h.torque_cmd[k - 1])) < 0.1


def test_impulse_cli_writes_the_plot(artifact_file, tmp_path, capsys):
    out = tmp_path / "imp"
    assert main(["impulse", "--controller", "nn", "--artifact", artifact_file, "--duration", "36",
                 "--out", str(out)]) == 0
    doc = json.loads((out / "impulse.json").read_text())
    assert doc["t_pid_first_s"] == pytest.approx(30.1) and doc["nn_back_after_impulse_end_s"] <= NN_BACK_WITHIN_S
    assert (out / "impulse.png").stat().st_size > 10_000
    assert "network back at" in capsys.readouterr().out
    assert main(["impulse", "--duration", "20", "--out", str(tmp_path / "x")]) == 2
