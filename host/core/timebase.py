"""UTC time tags and Greenwich mean sidereal time.

Time is kept as two numbers so float64 (and later float32 on board) keeps sub-millisecond
precision: ``jd_days`` is the Julian Day Number of the UTC calendar date (the integer Julian date
at that day's noon) and ``sec_of_day`` the UTC seconds since that date's midnight, so

    JD = jd_days - 0.5 + sec_of_day / 86400.

``sec_of_day`` may run past 86400 or below 0 (a simulation crossing midnight); ``normalise_time``
folds it back. UT1 = UTC is assumed (|UT1 - UTC| < 0.9 s, i.e. < 14 arcsec of Earth rotation;
the target and the orbit use the same time, so this only shifts the scenario, not the guidance
consistency). Leap seconds are not modelled (a leap second inside a run is not expected).

GMST: IAU-82 (Aoki et al. 1982), split into GMST at 0h UT1 plus the sidereal rate times the UT1
seconds of day, so no large number multiplies a fractional day.
"""
from __future__ import annotations

import numpy as np

from host.core.constants import SECONDS_PER_DAY

J2000_JD = 2451545.0
DAYS_PER_JULIAN_CENTURY = 36525.0


def julian_day_number(year: int, month: int, day: int) -> int:
    """Gregorian calendar date -> Julian Day Number (Fliegel & Van Flandern 1968, integer math)."""
    a = (14 - month) // 12
    y = year + 4800 - a
    m = month + 12 * a - 3
    return day + (153 * m + 2) // 5 + 365 * y + y // 4 - y // 100 + y // 400 - 32045


def utc_to_jd(year: int, month: int, day: int, hour: int = 0, minute: int = 0,
              second: float = 0.0) -> tuple[int, float]:
    """UTC calendar date and time -> (jd_days, sec_of_day)."""
    return julian_day_number(year, month, day), hour * 3600.0 + minute * 60.0 + float(second)


def normalise_time(jd_days, sec_of_day):
    """Fold sec_of_day into [0, 86400) and carry whole days into jd_days (works on arrays)."""
    carry = np.floor(np.asarray(sec_of_day, dtype=float) / SECONDS_PER_DAY)
    return np.asarray(jd_days) + carry.astype(np.int64), sec_of_day - carry * SECONDS_PER_DAY


def add_seconds(jd_days, sec_of_day, dt):
    """Time tag dt seconds later, normalised."""
    return normalise_time(jd_days, np.asarray(sec_of_day, dtype=float) + dt)


def julian_date(jd_days, sec_of_day):
    """Single float64 Julian date (loses ~20 us of precision; for display and coarse use only)."""
    return np.asarray(jd_days, dtype=float) - 0.5 + np.asarray(sec_of_day, dtype=float) / SECONDS_PER_DAY


def _centuries_at_midnight(jd_days, sec_of_day):
    jd_days, sec_of_day = normalise_time(jd_days, sec_of_day)
    tu0 = (np.asarray(jd_days, dtype=float) - 0.5 - J2000_JD) / DAYS_PER_JULIAN_CENTURY
    return tu0, sec_of_day


def _sidereal_ratio(tu0):
    """d(GMST)/d(UT1) from the IAU-82 polynomial (Aoki 1982 eq. 14): sidereal s per UT1 s."""
    return 1.002737909350795 + 5.9006e-11 * tu0 - 5.9e-15 * tu0 * tu0


def gmst(jd_days, sec_of_day):
    """Greenwich mean sidereal time [rad, in [0, 2pi)] from UTC (UT1 = UTC), IAU-82.

    GMST(0h UT1) = 24110.54841 + 8640184.812866 Tu + 0.093104 Tu^2 - 6.2e-6 Tu^3  (seconds),
    Tu in Julian centuries of UT1 from J2000 to that midnight; then add ratio * UT1 seconds.
    """
    tu0, s = _centuries_at_midnight(jd_days, sec_of_day)
    gmst0 = 24110.54841 + tu0 * (8640184.812866 + tu0 * (0.093104 - 6.2e-6 * tu0))
    gmst_s = np.mod(np.mod(gmst0, SECONDS_PER_DAY) + _sidereal_ratio(tu0) * s, SECONDS_PER_DAY)
    return gmst_s * (2.0 * np.pi / SECONDS_PER_DAY)


def gmst_rate(jd_days, sec_of_day):
    """d(GMST)/dt [rad/s]: the Earth's sidereal rotation rate consistent with ``gmst``."""
    tu0, _ = _centuries_at_midnight(jd_days, sec_of_day)
    return _sidereal_ratio(tu0) * (2.0 * np.pi / SECONDS_PER_DAY)
