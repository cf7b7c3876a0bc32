"""Network input preprocessing (paper 001 Sec. 4.2), shared by every controller.

From a Measurement: the desired state (host.gnc.guidance, analytic ω_d and ω̇_d instead of the
paper's n-step prediction eq. 10), then

    L_bd = L_bo · L_oi · L_di^T,   A_bd = euler312(L_bd),   ω_e = ω_b − ω_d.

ω_b is in S_b and ω_d in S_d; the paper subtracts them directly (the frames differ by A_bd,
≤ 0.02° in the envelope, so the mismatch is ≲ 3.5e-4·|ω_d|).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from host.core.constants import DEG
from host.control.controllers import Measurement
from host.core.frames import L_oi
from host.gnc.guidance import DesiredState, desired_state
from host.core.rotations import dcm_from_euler312, euler312_from_dcm


@dataclass(frozen=True)
class ControllerInputs:
    desired: DesiredState
    A_bd: np.ndarray        # rad, 3-1-2 Euler angles of S_b w.r.t. S_d
    omega_e: np.ndarray     # rad/s

    @property
    def omega_d(self) -> np.ndarray:
        return self.desired.omega_d

    @property
    def omegadot_d(self) -> np.ndarray:
        return self.desired.omegadot_d

    def network_inputs_deg(self) -> np.ndarray:
        """S_in of eq. 11 in the paper's units: [ω_d °/s, ω̇_d °/s², A_bd °, ω_e °/s] (12,)."""
        return np.concatenate([self.omega_d, self.omegadot_d, self.A_bd, self.omega_e]) / DEG


def preprocess(m: Measurement) -> ControllerInputs:
    d = desired_state(m.jd_days, m.sec_of_day, m.R_s, m.V_s, m.lon, m.lat)
    L_bd = dcm_from_euler312(m.A_bo) @ L_oi(m.R_s, m.V_s) @ d.L_di.T
    return ControllerInputs(desired=d, A_bd=euler312_from_dcm(L_bd),
                            omega_e=np.asarray(m.omega_b, float) - d.omega_d)
