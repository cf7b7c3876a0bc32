"""The central target, the 100 seeded staring targets and the CLI target parser."""
import json
import subprocess
import sys

import numpy as np
import pytest
from scipy import stats

from host.errors import HostError
from host.sim.targets import central_target, parse_target, staring_targets

D = np.pi / 180.0
R_MEAN = 6371008.8
RADIUS = 100e3


def great_circle(lon1, lat1, lon2, lat2, r=R_MEAN):
    """Haversine distance [m]."""
    s = np.sin((lat2 - lat1) / 2) ** 2 + np.cos(lat1) * np.cos(lat2) * np.sin((lon2 - lon1) / 2) ** 2
    return 2 * r * np.arcsin(np.sqrt(s))


def initial_bearing(lon1, lat1, lon2, lat2):
    y = np.sin(lon2 - lon1) * np.cos(lat2)
    x = np.cos(lat1) * np.sin(lat2) - np.sin(lat1) * np.cos(lat2) * np.cos(lon2 - lon1)
    return np.mod(np.arctan2(y, x), 2 * np.pi)


def polar_offsets():
    c = central_target()
    t = staring_targets()
    lon, lat = np.array([x.lon for x in t]), np.array([x.lat for x in t])
    return great_circle(c.lon, c.lat, lon, lat), initial_bearing(c.lon, c.lat, lon, lat)


def cap_cdf(d):
    """Area fraction of the 100 km spherical cap inside distance d (uniform-in-area truth)."""
    return (1 - np.cos(d / R_MEAN)) / (1 - np.cos(RADIUS / R_MEAN))


def test_central_target_is_120E_30N():
    c = central_target()
    assert c.lon == pytest.approx(120 * D, abs=1e-15) and c.lat == pytest.approx(30 * D, abs=1e-15)
    assert c.height == 0.0


def test_exactly_100_targets_same_list_in_calls_and_in_a_fresh_process():
    a, b = staring_targets(), staring_targets()
    assert len(a) == 100 and a == b and len({(x.lon, x.lat) for x in a}) == 100
    code = ("import json; from host.sim.targets import staring_targets; "
            "print(json.dumps([[t.lon.hex(), t.lat.hex()] for t in staring_targets()]))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={"PYTHONHASHSEED": "12345", "PATH": ""})
    assert json.loads(out.stdout) == [[t.lon.hex(), t.lat.hex()] for t in a]


def test_all_targets_within_100_km_of_the_centre():
    d, _ = polar_offsets()
    assert np.all(d <= RADIUS * (1 + 1e-12)) and np.all(d > 0)
    assert np.max(d) > 0.8 * RADIUS  # they fill the disc, not a smaller one


def test_targets_are_uniform_in_area():
    d, az = polar_offsets()
    # radial CDF of a uniform disc: F(d) = cap area fraction (~ (d/100 km)^2)
    assert stats.kstest(cap_cdf(d), "uniform").pvalue > 0.01
    assert stats.kstest(az / (2 * np.pi), "uniform").pvalue > 0.01


def test_radial_ks_rejects_a_uniform_in_radius_layout():
    # power check of the radial test above: the classic mistake, distance uniform in [0, 100 km],
    # has KS statistic max|u - u^2| = 0.25 against a 1 % critical value of ~0.16 for n = 100
    rng = np.random.default_rng(0)
    d_wrong = rng.random(100) * RADIUS
    assert stats.kstest(cap_cdf(d_wrong), "uniform").pvalue < 0.01


def test_parse_target_selectors():
    assert parse_target("central") == [central_target()]
    assert parse_target(" ALL ") == staring_targets()
    (t,) = parse_target("-75.5,40.25")
    assert t.lon == pytest.approx(-75.5 * D) and t.lat == pytest.approx(40.25 * D) and t.height == 0.0
    assert parse_target("359.9,-90")[0].lat == pytest.approx(-90 * D)


@pytest.mark.parametrize("bad", ["", "centre", "120", "120,30,5", "a,b", "120,90.5", "120,-91",
                                 "360,0", "-180.01,0", "nan,10", "10,inf"])
def test_parse_target_rejects_bad_input_with_one_line(bad):
    with pytest.raises(HostError) as e:
        parse_target(bad)
    assert "\n" not in str(e.value) and str(e.value)
