"""The scenario file (host.sim.scenario_file): round trip, the table6 reading resolved bit for bit
to TABLE6_ERRORS, the "norm" and "k sigma" arithmetic, the seal, and a corpus of bad files each
refused with one line naming the key. Expected numbers are computed here from the schema's
definitions (docs/scenario.md), not taken from the module."""
from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import pytest

from host.core.constants import ARCSEC, DEG
from host.plant.error_model import TABLE6_ERRORS
from host.sim import scenario_file as sf

# The schema's example, written by hand (no seal: `seal` inserts it).
VALID_BODY = """\
# a hand-written scenario
format = "staregen.scenario"
version = 1
reading = "table6"

[star_sensor]               # on each 3-1-2 angle of A_bo
constant_arcsec = [3.0, 3.0, 3.0]
random_arcsec = [3.0, 3.0, 3.0]
random_is = "3sigma"
random_applies_to = "axis"
noise_period_s = 0.1

[gyro]
constant_deg_per_h = [0.15, 0.15, 0.15]
random_deg_per_h = [0.15, 0.15, 0.15]
random_is = "1sigma"
random_applies_to = "axis"
noise_period_s = 0.1

[wheels]
constant_Nm = [0.01, 0.01, 0.01]
random_Nm = [0.01, 0.01, 0.01]
random_is = "1sigma"
random_applies_to = "axis"
noise_period_s = 0.1
"""


def _replace(old: str, new: str):
    def edit(text: str) -> str:
        assert old in text, old
        return text.replace(old, new, 1)
    return edit


def _gyro_line(old: str, new: str):
    """Replace `old` inside the [gyro] table only (the three tables share key names)."""
    def edit(text: str) -> str:
        head, _, tail = text.partition("[gyro]")
        assert old in tail, old
        return head + "[gyro]" + tail.replace(old, new, 1)
    return edit


def _drop_table(text: str, table: str) -> str:
    start = text.index(f"[{table}]")
    end = text.find("\n[", start + 1)
    return text[:start] + (text[end + 1:] if end >= 0 else "")


# (id, edit of the valid text, or bytes to write, the key the one-line message must name)
BAD_FILES = [
    ("string-for-number", _replace("constant_arcsec = [3.0, 3.0, 3.0]", 'constant_arcsec = [3.0, "3", 3.0]'),
     "star_sensor.constant_arcsec[1]"),
    ("string-for-period", _gyro_line("noise_period_s = 0.1", 'noise_period_s = "0.1"'), "gyro.noise_period_s"),
    ("bool-for-number", _gyro_line("noise_period_s = 0.1", "noise_period_s = true"), "gyro.noise_period_s"),
    ("bool-in-array", _replace("random_Nm = [0.01, 0.01, 0.01]", "random_Nm = [0.01, false, 0.01]"),
     "wheels.random_Nm[1]"),
    ("two-element-array", _replace("random_Nm = [0.01, 0.01, 0.01]", "random_Nm = [0.01, 0.01]"), "wheels.random_Nm"),
    ("four-element-array", _replace("constant_Nm = [0.01, 0.01, 0.01]", "constant_Nm = [0.01, 0.01, 0.01, 0.01]"),
     "wheels.constant_Nm"),
    ("scalar-for-array", _replace("random_arcsec = [3.0, 3.0, 3.0]", "random_arcsec = 3.0"), "star_sensor.random_arcsec"),
    ("negative-random", _replace("random_arcsec = [3.0, 3.0, 3.0]", "random_arcsec = [3.0, -1.0, 3.0]"),
     "star_sensor.random_arcsec[1]"),
    ("unknown-key", _gyro_line("random_is", "drift = 1.0\nrandom_is"), "gyro.drift"),
    ("unknown-top-key", _replace('reading = "table6"', 'reading = "table6"\nauthor = "me"'), "author"),
    ("unknown-table", lambda t: t + "\n[magnetometer]\nconstant = [1.0, 1.0, 1.0]\n", "magnetometer"),
    ("missing-key", _replace("random_Nm = [0.01, 0.01, 0.01]\n", ""), "wheels.random_Nm"),
    ("missing-table", lambda t: _drop_table(t, "gyro"), "gyro: missing table"),
    ("missing-reading", _replace('reading = "table6"\n', ""), "reading"),
    ("table-is-a-value", lambda t: _drop_table(t, "gyro").replace('reading = "table6"', 'reading = "table6"\ngyro = 5'),
     "gyro: must be a table"),
    ("nan", _replace("constant_Nm = [0.01, 0.01, 0.01]", "constant_Nm = [nan, 0.01, 0.01]"), "wheels.constant_Nm[0]"),
    ("inf", _replace("random_arcsec = [3.0, 3.0, 3.0]", "random_arcsec = [3.0, 3.0, inf]"),
     "star_sensor.random_arcsec[2]"),
    ("minus-inf-constant", _gyro_line("constant_deg_per_h = [0.15, 0.15, 0.15]",
                                      "constant_deg_per_h = [-inf, 0.15, 0.15]"), "gyro.constant_deg_per_h[0]"),
    ("inf-period", _gyro_line("noise_period_s = 0.1", "noise_period_s = inf"), "gyro.noise_period_s"),
    ("period-zero", _gyro_line("noise_period_s = 0.1", "noise_period_s = 0"), "gyro.noise_period_s"),
    ("period-negative", _gyro_line("noise_period_s = 0.1", "noise_period_s = -0.1"), "gyro.noise_period_s"),
    ("period-tiny", _gyro_line("noise_period_s = 0.1", "noise_period_s = 1e-300"), "gyro.noise_period_s"),
    ("period-too-long", _gyro_line("noise_period_s = 0.1", "noise_period_s = 3601.0"), "gyro.noise_period_s"),
    ("absurd-magnitude", _replace("constant_arcsec = [3.0, 3.0, 3.0]", "constant_arcsec = [3.0, 1e12, 3.0]"),
     "star_sensor.constant_arcsec[1]"),
    ("huge-integer", _replace("constant_arcsec = [3.0, 3.0, 3.0]", f"constant_arcsec = [3.0, {10 ** 400}, 3.0]"),
     "star_sensor.constant_arcsec[1]"),
    ("bad-random-is", _gyro_line('random_is = "1sigma"', 'random_is = "4sigma"'), "gyro.random_is"),
    ("random-is-number", _gyro_line('random_is = "1sigma"', "random_is = 1"), "gyro.random_is"),
    ("bad-applies-to", _gyro_line('random_applies_to = "axis"', 'random_applies_to = "vector"'),
     "gyro.random_applies_to"),
    ("norm-unequal", lambda t: _gyro_line('random_applies_to = "axis"', 'random_applies_to = "norm"')(t).replace(
        "random_deg_per_h = [0.15, 0.15, 0.15]", "random_deg_per_h = [0.15, 0.3, 0.15]"), "gyro.random_deg_per_h"),
    ("bad-reading-name", _replace('reading = "table6"', 'reading = "Table 6"'), "reading"),
    ("reading-too-long", _replace('reading = "table6"', f'reading = "{"a" * 41}"'), "reading"),
    ("reading-not-string", _replace('reading = "table6"', "reading = 6"), "reading"),
    ("wrong-format", _replace('format = "staregen.scenario"', 'format = "staregen.controller-config"'), "format"),
    ("wrong-version", _replace("version = 1", "version = 2"), "version"),
    ("float-version", _replace("version = 1", "version = 1.0"), "version"),
    ("missing-version", _replace("version = 1\n", ""), "version"),
    ("newline-in-key", _gyro_line("random_is", '"evil\\nkey" = 1\nrandom_is'), "gyro."),
    ("bad-toml-syntax", _replace("random_is = \"3sigma\"", "random_is = "), "not valid TOML"),
    ("duplicate-key", _gyro_line("random_is", 'random_is = "1sigma"\nrandom_is'), "not valid TOML"),
    ("non-utf8", lambda t: t.encode("utf-8").replace(b"hand-written", b"hand-\xff\xfewritten"), "not UTF-8"),
    ("too-large", lambda t: t + ("# padding padding padding padding padding padding padding\n" * 1200), "KiB"),
]


@pytest.fixture
def valid_file(tmp_path) -> Path:
    path = tmp_path / "scenario.toml"
    path.write_text(VALID_BODY, encoding="utf-8")
    sf.seal(path)
    return path


def write_bad(tmp_path: Path, edit) -> Path:
    """The valid text with one edit, sealed as the valid file is (so the seal is not what fails)."""
    path = tmp_path / "bad.toml"
    text = edit(VALID_BODY)
    data = text if isinstance(text, bytes) else text.encode("utf-8")
    path.write_bytes(data)
    return path


def assert_one_line(message: str, path: Path, key: str) -> None:
    assert len(message.splitlines()) == 1, message
    assert "\n" not in message and "\r" not in message
    assert message.startswith(f"{path}: "), message
    assert key in message, message
    assert len(message) < 400, message


# ----------------------------------------------------------------------------- resolution


def test_table6_resolves_exactly_to_table6_errors(valid_file):
    for scenario in (sf.from_reading("table6"), sf.load(valid_file)):
        e = scenario.errors
        assert e == TABLE6_ERRORS
        # bit for bit, from the schema: bias = value·unit, σ = value/k·unit
        assert e.star.bias == (3.0 * ARCSEC,) * 3
        assert e.star.sigma == (1.0 * ARCSEC,) * 3
        deg_per_hour = DEG / 3600.0
        assert e.gyro.bias == (0.15 * deg_per_hour,) * 3 and e.gyro.sigma == (0.15 * deg_per_hour,) * 3
        assert e.wheels.bias == (0.01,) * 3 and e.wheels.sigma == (0.01,) * 3
        assert (e.star.period, e.gyro.period, e.wheels.period) == (0.1, 0.1, 0.1)
        assert e.reading == "table6"


def test_resolve_norm_and_k_sigma(tmp_path):
    text = (VALID_BODY.replace('reading = "table6"', 'reading = "norm-2sigma"')
            .replace("random_arcsec = [3.0, 3.0, 3.0]", "random_arcsec = [6.0, 6.0, 6.0]")
            .replace('random_is = "3sigma"\nrandom_applies_to = "axis"', 'random_is = "2sigma"\nrandom_applies_to = "norm"'))
    text = _gyro_line('random_is = "1sigma"', 'random_is = "2sigma"')(text)   # per axis, 2σ
    path = tmp_path / "norm.toml"
    path.write_text(text, encoding="utf-8")
    sf.seal(path)
    e = sf.load(path).errors
    # "norm": the stated value is k times the RMS of |e|; with iid axes E|e|² = 3σ², so σ = v/(k·√3)
    expected_star = 6.0 * (math.pi / 180.0 / 3600.0) / (2.0 * 3.0 ** 0.5)
    for s in e.star.sigma:
        assert math.isclose(s, expected_star, rel_tol=1e-15)
    assert e.star.bias == (3.0 * ARCSEC,) * 3          # constants are per axis whatever the random part
    for s in e.gyro.sigma:
        assert math.isclose(s, 0.075 * math.pi / 180.0 / 3600.0, rel_tol=1e-15)
    assert e.reading == "norm-2sigma"


def test_constants_keep_their_sign_and_integers_read_as_reals(tmp_path):
    text = VALID_BODY.replace("constant_Nm = [0.01, 0.01, 0.01]", "constant_Nm = [-0.02, 0, 5]")
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    sf.seal(path)
    e = sf.load(path).errors
    assert e.wheels.bias == (-0.02, 0.0, 5.0)
    assert all(isinstance(x, float) for x in e.wheels.bias)


# ----------------------------------------------------------------------------- round trip and seal


def test_round_trip(tmp_path):
    values = json.loads(json.dumps(sf.default_scenario().values))
    values["reading"] = "custom_1"
    values["gyro"]["constant_deg_per_h"] = [-0.5, 0.25, 1.0]
    values["wheels"]["random_is"] = "2sigma"
    custom = sf.from_values(values)
    for scenario in (sf.default_scenario(), custom):
        path = sf.write(scenario, tmp_path / f"{scenario.reading}.toml")
        loaded = sf.load(path)
        assert loaded.values == scenario.values
        assert loaded.sha256 == scenario.sha256
        assert loaded.errors == scenario.errors
        assert loaded.reading == scenario.reading
        assert loaded.file == str(path)
    assert custom.sha256 != sf.default_scenario().sha256


def test_seal_is_sha256_of_the_documented_canonical_form(valid_file):
    """docs/scenario.md: JSON of format, version, reading and the tables, sorted keys, no
    whitespace, reals as float.hex."""
    import tomllib
    data = tomllib.loads(valid_file.read_text(encoding="utf-8"))
    stated = data.pop("sha256")

    def canonical(v):
        if isinstance(v, float):
            return v.hex()
        if isinstance(v, list):
            return [canonical(x) for x in v]
        if isinstance(v, dict):
            return {k: canonical(x) for k, x in v.items()}
        return v

    text = json.dumps(canonical(data), sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    assert stated == hashlib.sha256(text.encode("ascii")).hexdigest()
    assert sf.load(valid_file).sha256 == stated
    # 3 and 3.0 are one value, so one seal
    assert sf.values_sha256(data) == sf.values_sha256(
        json.loads(json.dumps(data).replace("3.0", "3")))


def test_hand_edit_refused_until_sealed_and_comments_survive(valid_file):
    before = sf.load(valid_file).sha256
    text = valid_file.read_text(encoding="utf-8")
    edited = _gyro_line("noise_period_s = 0.1", "noise_period_s = 0.02   # white at the plant step")(text)
    edited = edited.replace("[wheels]", "# my note on the wheels\n[wheels]")
    valid_file.write_text(edited, encoding="utf-8")
    with pytest.raises(sf.ScenarioError) as err:
        sf.load(valid_file)
    message = str(err.value)
    assert_one_line(message, valid_file, "sha256")
    assert "staregen scenario seal" in message
    digest, changed = sf.seal(valid_file)
    assert changed and digest != before
    after = valid_file.read_text(encoding="utf-8")
    for comment in ("# a hand-written scenario", "# on each 3-1-2 angle of A_bo", "# white at the plant step",
                    "# my note on the wheels"):
        assert comment in after
    assert after.count("sha256") == 1
    loaded = sf.load(valid_file)
    assert loaded.sha256 == digest and loaded.errors.gyro.period == 0.02
    assert sf.seal(valid_file) == (digest, False)


def test_missing_seal_is_refused_then_added(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(VALID_BODY, encoding="utf-8")
    with pytest.raises(sf.ScenarioError) as err:
        sf.load(path)
    assert_one_line(str(err.value), path, "sha256")
    assert "staregen scenario seal" in str(err.value)
    digest, changed = sf.seal(path)
    assert changed and sf.load(path).sha256 == digest


def test_describe_is_json_and_names_the_file(valid_file):
    d = sf.load(valid_file).describe()
    assert json.loads(json.dumps(d)) == d
    assert d["file"] == str(valid_file) and d["reading"] == "table6"
    assert d["sha256"] == sf.load(valid_file).sha256
    assert d["values"]["star_sensor"]["random_is"] == "3sigma" and "sha256" not in d["values"]
    assert sf.default_scenario().describe()["file"] is None


def test_readings_and_unknown_reading():
    assert "table6" in sf.READINGS
    description, _ = sf.READINGS["table6"]
    assert len(description.splitlines()) == 1
    with pytest.raises(sf.ScenarioError) as err:
        sf.from_reading("table7")
    assert len(str(err.value).splitlines()) == 1 and "table6" in str(err.value)


def test_write_refuses_a_directory(tmp_path):
    with pytest.raises(sf.ScenarioError) as err:
        sf.write(sf.default_scenario(), tmp_path)
    assert len(str(err.value).splitlines()) == 1


# ----------------------------------------------------------------------------- bad files


def test_corpus_edits_apply():
    """Every edit changes the valid text (a no-op edit would test nothing)."""
    for name, edit, _ in BAD_FILES:
        out = edit(VALID_BODY)
        assert (out if isinstance(out, bytes) else out.encode()) != VALID_BODY.encode(), name


@pytest.mark.parametrize("name, edit, key", BAD_FILES, ids=[c[0] for c in BAD_FILES])
def test_bad_file_is_one_line_naming_the_key(tmp_path, name, edit, key):
    path = write_bad(tmp_path, edit)
    with pytest.raises(sf.ScenarioError) as err:
        sf.load(path)
    assert_one_line(str(err.value), path, key)
    with pytest.raises(sf.ScenarioError) as err:   # sealing refuses the same file the same way
        sf.seal(path)
    assert_one_line(str(err.value), path, key)
