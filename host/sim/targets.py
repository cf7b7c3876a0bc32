"""Ground targets of the staring scenario (paper 001 sec. 7.1, Fig. 5).

The central target is 120 deg E, 30 deg N (height 0 on WGS-84). The 100 staring targets are drawn
uniformly in area inside the 100 km circle around it, on the mean sphere (R = 6371.0088 km):
great-circle distance d with P(D <= d) = (1 - cos(d/R)) / (1 - cos(D/R)), azimuth uniform, then
the spherical direct problem from the centre. The geodetic latitude of the centre is used as the
spherical latitude; the distortion against true WGS-84 geodesics (< 0.4 % of the distance) does not
matter for "100 targets spread over a 100 km disc". A fixed seed makes the list the same on every
run and machine (numpy PCG64).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from functools import lru_cache

import numpy as np

from codegen import reading
from codegen.number_text import parse_real
from host.core.constants import DEG, EARTH_MEAN_RADIUS
from host.errors import HostError

CENTRAL_LON_DEG = 120.0
CENTRAL_LAT_DEG = 30.0
N_STARING_TARGETS = 100
STARING_RADIUS_M = 100e3
STARING_SEED = 20170531


@dataclass(frozen=True)
class Target:
    name: str
    lon: float          # rad, geodetic longitude (east positive)
    lat: float          # rad, geodetic latitude
    height: float = 0.0  # m above the WGS-84 ellipsoid

    @property
    def lon_deg(self) -> float:
        return self.lon / DEG

    @property
    def lat_deg(self) -> float:
        return self.lat / DEG


def central_target() -> Target:
    return Target("central", CENTRAL_LON_DEG * DEG, CENTRAL_LAT_DEG * DEG)


def destination_point(lon0, lat0, distance, azimuth, radius: float = EARTH_MEAN_RADIUS):
    """Spherical direct problem: the point at great-circle ``distance`` [m] along ``azimuth``
    [rad, from north through east] from (lon0, lat0) [rad]. Returns (lon, lat) in rad."""
    delta = np.asarray(distance, dtype=float) / radius
    lat = np.arcsin(np.sin(lat0) * np.cos(delta) + np.cos(lat0) * np.sin(delta) * np.cos(azimuth))
    lon = lon0 + np.arctan2(np.sin(azimuth) * np.sin(delta) * np.cos(lat0),
                            np.cos(delta) - np.sin(lat0) * np.sin(lat))
    return lon, lat


def uniform_disc_offsets(n: int, radius_m: float, seed: int, sphere_radius: float = EARTH_MEAN_RADIUS):
    """n (distance [m], azimuth [rad]) pairs uniform in area on a spherical cap of radius_m."""
    rng = np.random.default_rng(seed)
    u, v = rng.random(n), rng.random(n)
    cap = 1.0 - np.cos(radius_m / sphere_radius)
    distance = sphere_radius * np.arccos(1.0 - u * cap)  # inverse CDF of the cap area
    return distance, 2.0 * np.pi * v


@lru_cache(maxsize=1)
def _staring_targets() -> tuple[Target, ...]:
    c = central_target()
    d, az = uniform_disc_offsets(N_STARING_TARGETS, STARING_RADIUS_M, STARING_SEED)
    lon, lat = destination_point(c.lon, c.lat, d, az)
    return tuple(Target(f"T{k:03d}", float(lo), float(la)) for k, (lo, la) in enumerate(zip(lon, lat)))


def staring_targets() -> list[Target]:
    """The 100 seeded targets within 100 km of the central target (same list on every run)."""
    return list(_staring_targets())


def parse_target(text: str) -> list[Target]:
    """CLI target selector: "central", "all" (the 100 staring targets) or "LON,LAT" in degrees.

    Raises HostError (one line) on anything else, latitude outside [-90, 90] or longitude outside
    [-180, 360).
    """
    key = text.strip().lower()
    if key == "central":
        return [central_target()]
    if key == "all":
        return staring_targets()
    parts = key.split(",")
    try:
        if len(parts) != 2:
            raise ValueError
        lon_deg, lat_deg = parse_real(parts[0]), parse_real(parts[1])   # ASCII digits: no `1_20`
    except ValueError:
        raise HostError(f"unknown target {text!r}: expected 'central', 'all' or 'LON,LAT' in degrees") from None
    if not (np.isfinite(lon_deg) and np.isfinite(lat_deg)):
        raise HostError(f"target {text!r}: longitude and latitude must be finite numbers")
    if not -90.0 <= lat_deg <= 90.0:
        raise HostError(f"target latitude {lat_deg:g} deg is outside [-90, 90]")
    if not -180.0 <= lon_deg < 360.0:
        raise HostError(f"target longitude {lon_deg:g} deg is outside [-180, 360)")
    return [Target(f"{lon_deg:g},{lat_deg:g}", lon_deg * DEG, lat_deg * DEG)]


MAX_TARGET_ROWS = 10_000


def load_target_list(path) -> list[Target]:
    """A target list file: one target per line, `LON,LAT` or `NAME,LON,LAT` (degrees, geodetic);
    blank lines and `#` comments ignored. Any bad row is a one-line HostError naming the line."""
    p = Path(path)
    try:
        text = reading.read_text(p)      # capped, regular files only
    except reading.InputFileError as exc:
        raise HostError(f"{exc} (target list)") from None
    targets = []
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        parts = [s.strip() for s in line.split(",")]
        if len(parts) not in (2, 3):
            raise HostError(f"{p}:{number}: expected LON,LAT or NAME,LON,LAT in degrees, got {line[:60]!r}")
        name = parts[0] if len(parts) == 3 else None
        if name is not None and not (name.isprintable() and 0 < len(name) <= 40):
            raise HostError(f"{p}:{number}: a target name must be 1-40 printable characters")
        try:
            (target,) = parse_target(",".join(parts[-2:]))
        except HostError as exc:
            raise HostError(f"{p}:{number}: {exc}") from None
        targets.append(Target(name or target.name, target.lon, target.lat))
        if len(targets) > MAX_TARGET_ROWS:
            raise HostError(f"{p}: more than {MAX_TARGET_ROWS} targets")
    if not targets:
        raise HostError(f"{p}: no targets in the file")
    return targets
