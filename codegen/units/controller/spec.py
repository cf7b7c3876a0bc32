"""What the generated flight controller (paper 001 Fig. 2) is, in numbers shared by its three
implementations: the float64 twin (host/control/nn_controller.py), the generated C
(codegen/templates/controller.*.j2) and the float32 golden model (codegen/golden_controller.py).

The host fills a ControllerConfig from its own constants (host.control.nn_controller.flight_config), so
codegen never imports the simulator. Status word bits and the time base are fixed here.
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

# ----------------------------------------------------------------------------- status word
STATUS_PID = 1 << 0              # the PID law commanded this step (0: the network did)
STATUS_BOUND_SHIFT = 1           # bit 1 + i: network input i (Table 2 order) outside its bounds or NaN
N_BOUNDS = 12
STATUS_INPUT_INVALID = 1 << 13   # a non-finite input field, or UTC day / ms out of range
STATUS_SATURATED = 1 << 14       # at least one torque axis clipped to the wheel limit
STATUS_DWELL = 1 << 15           # inside the envelope, PID still flying until the dwell ends
STATUS_STATE_REPAIRED = 1 << 16  # the caller's state held a non-finite or out-of-limit integrator: reset to 0
STATUS_INTEGRITY = 1 << 17       # the network's constant tables failed their CRC-32 (at init or a check): PID only
STATUS_BOUNDS_MASK = ((1 << N_BOUNDS) - 1) << STATUS_BOUND_SHIFT

MODE_NN, MODE_PID = 0, 1

# Target latitude as a binary angle (LSB = pi * 2^-31 rad): |lat| <= 2^30 is [-90, 90] deg; beyond
# it the geometry would silently aim at the mirrored latitude, so it is an invalid input.
LAT_BAM_MAX = 1 << 30

# ----------------------------------------------------------------------------- time base
# UTC on board: utc_day = days since 2000-01-01 (= Julian Day Number - 2451545, the JDN of that
# date) and utc_ms = milliseconds since that day's UTC midnight (86,400,000 + 1,000 for a leap second).
J2000_JDN = 2451545
UTC_MS_MAX = 86_401_000          # exclusive
UTC_DAY_MIN, UTC_DAY_MAX = -36_525, 73_050   # accepted 1900 .. 2200; accuracy stated for 2000 .. 2100
# GMST (IAU-82, the host's host.core.timebase.gmst) in Q64 turns, all integer:
#   q = GMST_A + GMST_B * d + GMST_Q * (2d - 1)^2 + GMST_R * ms   (mod 2^64)
# from GMST(0h) = 24110.54841 + 8640184.812866 Tu + 0.093104 Tu^2 s, Tu = (d - 0.5) / 36525, plus
# 1.002737909350795 sidereal s per UT1 s. Dropped: the -6.2e-6 Tu^3 s term (< 1e-4 arcsec) and the
# Tu dependence of the ratio (< 1e-4 arcsec over a day).
_S_PER_DAY = Fraction(86400)
_CENT = Fraction(36525)


def _q64(x: Fraction) -> int:
    return round((x - (x.numerator // x.denominator)) * (1 << 64)) % (1 << 64)


GMST_A = _q64((Fraction("24110.54841") - Fraction("8640184.812866") / (2 * _CENT)) / _S_PER_DAY)
GMST_B = _q64(Fraction("8640184.812866") / _CENT / _S_PER_DAY)
GMST_Q = round(Fraction("0.093104") / (4 * _CENT * _CENT) / _S_PER_DAY * (1 << 64))
GMST_R = round(Fraction("1.002737909350795") / (_S_PER_DAY * 1000) * (1 << 64))


@dataclass(frozen=True)
class ControllerConfig:
    """Everything besides the network that the generated controller bakes in (SI unless stated)."""
    kp: tuple[float, float, float]            # N·m/deg (Table 1)
    ki: tuple[float, float, float]            # N·m/(deg·s)
    kd: tuple[float, float, float]            # N·m/(deg/s)
    torque_limit: float                       # N·m per axis
    control_period: float                     # s, the PID integrator's step
    dwell_steps: int                          # consecutive in-envelope steps before the NN resumes
    integral_limit: float                     # deg·s, |integrator| bound (keeps the state finite)
    earth_a: float                            # m, WGS-84 semi-major axis
    earth_e2: float                           # WGS-84 first eccentricity squared
    earth_rate: float                         # rad/s, sidereal rate (d GMST / dt)
    mu: float                                 # m^3/s^2
    pid_only: bool = False                    # envelope emitted empty: every step flies the PID branch
