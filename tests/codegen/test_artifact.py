"""Model artifact: exact round trip, one test per rejection rule, MATLAB mapminmax/tansig hand-checks, CLI."""
import copy
import json
import math

import numpy as np
import pytest
import torch

import host.cli as cli
from codegen import artifact as art
from codegen.errors import CodegenError
from codegen.units.network import golden
from host.control.nn_controller import load_artifact

CODEGEN_COMMANDS = ["host.cli.artifact", "host.cli.codegen", "host.cli.c_eval", "host.cli.verify"]


@pytest.fixture(scope="module")
def artifact():
    return art.random_artifact((12, 40, 3), seed=3)


@pytest.fixture()
def document(artifact):
    return copy.deepcopy(artifact.document())


def reseal(doc):
    """Recompute the sha256 so a test exercises one rule, not the seal."""
    doc["sha256"] = art.payload_sha256(doc["payload"])
    return doc


def rejection(tmp_path, doc) -> art.ArtifactError:
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(art.ArtifactError) as info:
        art.load(path)
    assert str(path) in str(info.value)
    return info.value


def run_cli(monkeypatch, capsys, *argv):
    monkeypatch.setattr(cli, "COMMANDS", CODEGEN_COMMANDS)
    code = cli.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def bits(a):
    return np.asarray(a, dtype=np.float32).view(np.uint32)


# ----------------------------------------------------------------------------- round trip

def test_save_and_load_round_trip_bit_exact(artifact, tmp_path):
    path = artifact.save(tmp_path / "a.json")
    back = art.load(path)
    assert back.sha256 == artifact.sha256
    for name in ("W1", "b1", "W2", "b2"):
        np.testing.assert_array_equal(bits(getattr(back, name)), bits(getattr(artifact, name)))
    np.testing.assert_array_equal(bits(back.input_map.gain), bits(artifact.input_map.gain))
    np.testing.assert_array_equal(back.input_map.xmin.view(np.uint64), artifact.input_map.xmin.view(np.uint64))
    assert [p.name for p in tmp_path.iterdir()] == ["a.json"]  # no temporary left behind


def test_random_artifact_is_deterministic_in_its_seed():
    assert art.random_artifact((5, 17, 2), 7).sha256 == art.random_artifact((5, 17, 2), 7).sha256
    assert art.random_artifact((5, 17, 2), 7).sha256 != art.random_artifact((5, 17, 2), 8).sha256


def test_twelve_inputs_default_to_table2_other_shapes_get_a_synthetic_envelope():
    a = art.random_artifact((12, 40, 3), 0)
    assert a.envelope.names[1] == "omega_d_y" and a.envelope.units[4] == "deg/s^2"
    assert a.envelope.min[1] == np.float32(-1.2) and a.envelope.max[1] == 0.0
    assert a.envelope.max[9] == np.float32(0.004)
    b = art.random_artifact((5, 17, 2), 0)
    assert b.envelope.source.startswith("synthetic") and b.envelope.min.shape == (5,)
    assert np.all(b.envelope.min < b.envelope.max)


# ----------------------------------------------------------------------------- rejection rules

def test_rejects_wrong_version(tmp_path, document):
    document["version"] = 2
    err = rejection(tmp_path, document)
    assert err.field_path == "version" and "unsupported artifact version 2" in err.reason


def test_rejects_missing_field(tmp_path, document):
    del document["payload"]["normalisation"]["input"]["gain"]
    err = rejection(tmp_path, reseal(document))
    assert err.field_path == "payload.normalisation.input.gain" and err.reason == "missing field"


def test_rejects_shape_mismatch_of_a_weight_row(tmp_path, document):
    document["payload"]["network"]["layers"][0]["weights"][3].pop()
    err = rejection(tmp_path, reseal(document))
    assert err.field_path == "payload.network.layers[0].weights[3]"
    assert "shape mismatch: expected 12 entries, got 11" in err.reason


def test_rejects_sizes_that_disagree_with_the_weights(tmp_path, document):
    document["payload"]["network"]["sizes"][1] = 41
    err = rejection(tmp_path, reseal(document))
    assert err.field_path == "payload.network.layers[0].weights"
    assert "shape mismatch: expected 41 rows" in err.reason


@pytest.mark.parametrize("value", ["inf", "-inf", "nan"])
def test_rejects_non_finite_weight(tmp_path, document, value):
    document["payload"]["network"]["layers"][1]["weights"][2][7] = value
    err = rejection(tmp_path, reseal(document))
    assert err.field_path == "payload.network.layers[1].weights[2][7]" and "non-finite" in err.reason


def test_rejects_zero_gain(tmp_path, document):
    document["payload"]["normalisation"]["output"]["gain"][1] = "0x0p+0"
    err = rejection(tmp_path, reseal(document))
    assert err.field_path == "payload.normalisation.output.gain[1]"
    assert "gain must be finite and non-zero" in err.reason


@pytest.mark.parametrize("value", ["inf", "nan"])
def test_rejects_non_finite_gain(tmp_path, document, value):
    document["payload"]["normalisation"]["input"]["gain"][5] = value
    err = rejection(tmp_path, reseal(document))
    assert err.field_path == "payload.normalisation.input.gain[5]"
    assert "gain must be finite and non-zero" in err.reason


@pytest.mark.parametrize("shift", [0, 1])
def test_rejects_envelope_min_not_below_max(tmp_path, document, shift):
    env = document["payload"]["envelope"]
    env["min"][4] = art.hex_float(float(np.float32(float.fromhex(env["max"][4])) + np.float32(shift)))
    err = rejection(tmp_path, reseal(document))
    assert err.field_path == "payload.envelope.min[4]" and "must be < max" in err.reason


def test_rejects_sha256_mismatch(tmp_path, document):
    weights = document["payload"]["network"]["layers"][0]["weights"]
    weights[0][0] = art.hex_float(float(np.nextafter(np.float32(float.fromhex(weights[0][0])), np.float32(9))))
    err = rejection(tmp_path, document)  # valid payload, stale seal
    assert err.field_path == "sha256" and "mismatch" in err.reason


def test_rejects_value_not_exact_in_float32(tmp_path, document):
    document["payload"]["network"]["layers"][0]["bias"][0] = "0x1.0000001p+0"
    err = rejection(tmp_path, reseal(document))
    assert err.field_path == "payload.network.layers[0].bias[0]" and "float32" in err.reason


def test_rejects_gain_that_is_not_matlabs(tmp_path, document):
    document["payload"]["normalisation"]["output"]["gain"][2] = "0x1p+0"
    err = rejection(tmp_path, reseal(document))
    assert err.field_path == "payload.normalisation.output.gain[2]" and "mapminmax" in err.reason


def test_rejects_invalid_json_and_missing_file(tmp_path):
    bad = tmp_path / "x.json"
    bad.write_text("{not json")
    with pytest.raises(art.ArtifactError, match="not valid JSON"):
        art.load(bad)
    with pytest.raises(art.ArtifactError, match="no such file"):
        art.load(tmp_path / "missing.json")


def test_only_regular_files_are_read_and_reads_are_capped(tmp_path, monkeypatch):
    """Issue 25: the 64 MiB cap trusted st_size, so /dev/zero (size 0) was read until memory ran
    out (the CLI table has that row). Now a device, FIFO or folder is refused, and the cap counts
    the bytes actually read: /proc/self/status is a regular file whose st_size is 0."""
    with pytest.raises(art.ArtifactError, match=r"file: cannot read \(not a regular file\)"):
        art.load(tmp_path)
    monkeypatch.setattr(art, "MAX_FILE_BYTES", 100)
    with pytest.raises(art.ArtifactError, match="file: larger than 100 bytes"):
        art.load("/proc/self/status")


@pytest.mark.parametrize("shape", [(10_000, 10_000, 10_000), (10_000, 1_000, 10)])
def test_shapes_an_artifact_cannot_hold_are_refused_before_allocating(shape):
    """Issue 25: `artifact random --shape 10000-10000-10000` allocated 800 MB of float64 first."""
    assert art.n_parameters(shape) > art.MAX_PARAMETERS
    text = "-".join(map(str, shape))
    with pytest.raises(CodegenError, match="more than the 4,194,304 an artifact may hold"):
        art.parse_shape(text)
    with pytest.raises(CodegenError, match="more than the 4,194,304 an artifact may hold"):
        art.random_artifact(shape)
    assert art.parse_shape("12-10000-3") == (12, 10_000, 3)      # the largest the README names still fits
    assert art.random_artifact((12, 20_000, 3)).n_hidden == 20_000   # too large for flash, not for a file


def test_a_document_claiming_a_shape_no_artifact_may_hold_is_refused(tmp_path, document):
    document["payload"]["network"]["sizes"] = [10_000, 10_000, 10_000]
    err = rejection(tmp_path, reseal(document))
    assert err.field_path == "payload.network.sizes" and "may hold" in err.reason


def test_shape_digits_are_ascii():
    with pytest.raises(CodegenError, match="--shape"):
        art.parse_shape("\u0661\u0662-40-3")


def test_from_arrays_rejects_non_finite_weights_with_the_same_path():
    a = art.random_artifact((4, 3, 2), 0)
    W1 = a.W1.copy()
    W1[2, 1] = np.nan
    with pytest.raises(art.ArtifactError, match=r"payload\.network\.layers\[0\]\.weights\[2\]\[1\]: non-finite"):
        art.from_arrays(W1, a.b1, a.W2, a.b2, a.input_map.xmin, a.input_map.xmax,
                        a.output_map.xmin, a.output_map.xmax)


# ----------------------------------------------------------------------------- from_torch

def test_from_torch_copies_float32_weights_exactly():
    torch.manual_seed(0)
    model = torch.nn.Sequential(torch.nn.Linear(12, 40), torch.nn.Tanh(), torch.nn.Linear(40, 3))
    env = art.table2_envelope()
    a = art.from_torch(model, env.min.astype(float), env.max.astype(float), [-0.5] * 3, [0.5] * 3)
    np.testing.assert_array_equal(bits(a.W1), bits(model[0].weight.detach().numpy()))
    np.testing.assert_array_equal(bits(a.b2), bits(model[2].bias.detach().numpy()))
    assert a.envelope.source == art.TABLE2_SOURCE and a.outputs.units == ("N*m",) * 3
    assert a.metadata["creator"] == "staregen from_torch"


def test_from_torch_rejects_other_architectures():
    model = torch.nn.Sequential(torch.nn.Linear(4, 3), torch.nn.ReLU(), torch.nn.Linear(3, 1))
    with pytest.raises(art.ArtifactError, match=r"model: expected nn.Sequential\(Linear, Tanh, Linear\)"):
        art.from_torch(model, [0] * 4, [1] * 4, [0], [1])


# ----------------------------------------------------------------------------- MATLAB definitions

def test_mapminmax_matches_matlabs_documented_formula():
    """MATLAB: y = (ymax-ymin)*(x-xmin)/(xmax-xmin) + ymin, computed here in float64 independently."""
    xmin = np.array([-0.1, -1.2, 3.0, -7e-3])
    xmax = np.array([0.1, 0.0, 1000.0, 5e-3])
    m = art.mapminmax_settings(xmin, xmax)
    assert m.gain[2] == np.float32(2.0 / 997.0) and m.xoffset[1] == np.float32(-1.2)
    rng = np.random.default_rng(0)
    x = (xmin + rng.random((200, 4)) * (xmax - xmin)).astype(np.float32)
    a = art.from_arrays(np.ones((2, 4)), np.zeros(2), np.ones((1, 2)), np.zeros(1), xmin, xmax, [-2.0], [5.0],
                        envelope=(xmin, xmax))
    im, om = a.input_map, a.output_map  # applied as the artifact states them (float32; the C folds them)
    y = (x - im.xoffset) * im.gain + np.float32(im.ymin)
    assert y.dtype == np.float32
    y_matlab = 2.0 * (x.astype(np.float64) - xmin) / (xmax - xmin) - 1.0
    np.testing.assert_allclose(y, y_matlab, rtol=0, atol=4e-7)
    # Reverse: x = (xmax-xmin)*(y-ymin)/(ymax-ymin) + xmin on the output side [-2, 5].
    yn = np.linspace(-1, 1, 9, dtype=np.float32)[:, None]
    back = (yn - np.float32(om.ymin)) / om.gain + om.xoffset
    np.testing.assert_allclose(back[:, 0], 7.0 * (yn[:, 0].astype(np.float64) + 1.0) / 2.0 - 2.0, rtol=0, atol=1e-6)


def test_mapminmax_constant_row_rule():
    """MATLAB: a row with zero or non-finite range, or |gain| > 1e14, gets gain 1 and xoffset ymin."""
    m = art.mapminmax_settings([2.5, 0.0, 1.0, -1e308], [2.5, 1e-15, 3.0, 1e308])
    np.testing.assert_array_equal(m.gain, np.float32([1.0, 1.0, 1.0, 1.0]))
    np.testing.assert_array_equal(m.xoffset, np.float32([-1.0, -1.0, 1.0, -1.0]))
    m2 = art.mapminmax_settings([0.0], [1e-13])  # gain 2e13 <= 1e14: kept
    assert m2.gain[0] == np.float32(2e13) and m2.xoffset[0] == 0.0


def _matlab_tansig(n: float) -> float:
    return 2.0 / (1.0 + math.exp(-2.0 * n)) - 1.0


def test_tansig_matches_matlabs_definition_within_two_ulp():
    n = np.float32([0.0, 1e-3, -1e-3, 0.1, -0.37, 0.5, 1.0, -1.0, 2.0, -3.5, 5.0, 8.9, -9.5, 20.0])
    got = golden.tansig(n)
    want = np.array([_matlab_tansig(float(v)) for v in n])
    ulp = np.spacing(np.abs(want).astype(np.float32)).astype(np.float64)
    err_ulp = np.abs(got.astype(np.float64) - want) / ulp
    assert err_ulp.max() <= 2.0, dict(zip(n.tolist(), err_ulp.tolist()))


# ----------------------------------------------------------------------------- CLI

def test_cli_modules_are_registered():
    assert set(CODEGEN_COMMANDS) <= set(cli.COMMANDS)


def test_cli_random_then_check(monkeypatch, capsys, tmp_path):
    out_file = tmp_path / "r.json"
    code, out, _ = run_cli(monkeypatch, capsys, "artifact", "random", "--shape", "5-17-2", "--seed", "4",
                           "--out", str(out_file))
    assert code == 0 and "5-17-2" in out
    assert art.load(out_file).sha256 == art.random_artifact((5, 17, 2), 4).sha256
    code, out, _ = run_cli(monkeypatch, capsys, "artifact", "check", str(out_file))
    assert code == 0 and out.startswith(f"OK {out_file}: 5-17-2")


@pytest.mark.parametrize("argv, needle", [
    (["artifact", "check", "{bad}"], "payload.envelope.min[0]: envelope min"),
    (["artifact", "check", "{missing}"], "no such file"),
    (["artifact", "random", "--shape", "12-x-3", "--out", "{out}"], "--shape"),
    (["artifact", "random", "--out", "{mine}"], "exists and is not a staregen artifact; not overwritten"),
    (["artifact", "standin", "--out", "{mine}"], "exists and is not a staregen artifact; not overwritten"),
    (["artifact", "standin", "--out", "{folder}"], "is a directory (give a file name)"),
])
def test_cli_bad_input_gives_one_line_and_non_zero_exit(monkeypatch, capsys, tmp_path, document, argv, needle):
    bad = tmp_path / "bad.json"
    document["payload"]["envelope"]["min"][0] = document["payload"]["envelope"]["max"][0]
    bad.write_text(json.dumps(reseal(document)))
    mine = tmp_path / "mine.txt"
    mine.write_text("a user's file\n")
    paths = {"bad": str(bad), "missing": str(tmp_path / "nope.json"), "out": str(tmp_path / "o.json"),
             "mine": str(mine), "folder": str(tmp_path)}
    code, out, err = run_cli(monkeypatch, capsys, *[a.format(**paths) for a in argv])
    assert code != 0
    assert len(err.strip().splitlines()) == 1 and needle in err and "Traceback" not in err
    assert mine.read_text() == "a user's file\n"


def test_cli_standin_writes_the_stand_in_network(monkeypatch, capsys, tmp_path):
    """`artifact standin`: the network `simulate --controller nn-c` flies without --artifact (the README's
    Basilisk example generates its package from it); the fit is seeded, so the file is the same each time."""
    out_file = tmp_path / "standin.json"
    code, out, _ = run_cli(monkeypatch, capsys, "artifact", "standin", "--out", str(out_file))
    assert code == 0 and "12-40-3 stand-in" in out
    written = art.load(out_file)
    assert written.shape_text == "12-40-3"
    assert written.sha256 == load_artifact(None).sha256
