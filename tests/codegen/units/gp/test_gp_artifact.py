"""The GP artifact `staregen.gp-artifact` v1 (docs/gp-takeover.md §7): round trip, refusals, reference.

A hand-made model (no training, no gpytorch): Z spread in the normalised box, small m̃, R lower with
a positive diagonal.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from codegen import units
from codegen.artifact import ArtifactError, hex_float, payload_sha256
from codegen.errors import CodegenError
from codegen.units.gp import artifact as gpa

M = 6


def make(seed: int = 0, **over) -> gpa.GpArtifact:
    rng = np.random.default_rng(seed)
    R = np.tril(rng.normal(0, 0.05, (3, M, M)), -1) + np.stack([np.diag(rng.uniform(0.1, 0.5, M))] * 3)
    fields = dict(input_scale=np.array(gpa.INPUT_SCALES), output_scale=np.array([0.05, 0.08, 0.06]),
                  lengthscale=rng.uniform(0.8, 2.0, 9), outputscale=0.9, noise=np.array([0.01, 0.02, 0.015]),
                  jitter=1e-6, Z=rng.uniform(-1.5, 1.5, (M, 9)), m=rng.normal(0, 0.5, (3, M)), R=R)
    fields.update(over)
    return gpa.GpArtifact(arrays=gpa.GpArrays(**fields), envelope_min=-np.array(gpa.INPUT_SCALES),
                          envelope_max=np.array(gpa.INPUT_SCALES), metadata={"creator": "test", "seed": seed})


@pytest.fixture(scope="module")
def artifact():
    return make()


def reseal(doc: dict) -> dict:
    doc["sha256"] = payload_sha256(doc["payload"])
    return doc


def refused(doc, match: str, tmp_path, name="bad.json") -> str:
    path = tmp_path / name
    path.write_text(json.dumps(doc))
    with pytest.raises(ArtifactError) as info:
        gpa.load(path)
    text = str(info.value)
    assert "\n" not in text and text.startswith(f"{path}: ")
    assert match in text, text
    return text


def test_round_trip_is_byte_identical(tmp_path, artifact):
    path = artifact.save(tmp_path / "gp.json")
    loaded = gpa.load(path)
    assert loaded.to_json() == path.read_text() == artifact.to_json()
    assert loaded.sha256 == artifact.sha256
    doc = json.loads(path.read_text())
    assert doc["format"] == "staregen.gp-artifact" and doc["version"] == 1
    assert len(doc["payload"]["flight"]["A"]) == M * (M + 1) // 2
    assert len(doc["payload"]["variational"]["R"][0]) == M * (M + 1) // 2


def test_reference_from_loaded_equals_in_memory(tmp_path, artifact):
    loaded = gpa.load(artifact.save(tmp_path / "gp.json"))
    x = np.random.default_rng(3).uniform(-2, 2, (50, 9)) * np.array(gpa.INPUT_SCALES)
    for a, b in zip(gpa.reference_predict(loaded.arrays, x), gpa.reference_predict(artifact.arrays, x)):
        assert np.array_equal(a, b)
    for a, b in zip(gpa.flight_predict(loaded.flight, x[:, :3], x[:, 3:6]),
                    gpa.flight_predict(artifact.flight, x[:, :3], x[:, 3:6])):
        assert np.array_equal(a, b)


def test_flight_arrays_are_the_folded_model(artifact):
    a = artifact.arrays
    fl = artifact.flight
    assert all(v.dtype == np.float32 for v in fl.values())
    L = a.chol()
    A = np.zeros((M, M))
    A[np.tril_indices(M)] = fl["A"]
    assert np.allclose(A @ L, a.outputscale * np.eye(M), atol=1e-5 * np.abs(A).max() * np.abs(L).max() * M)
    x = np.random.default_rng(5).uniform(-1, 1, (40, 9)) * np.array(gpa.INPUT_SCALES)
    x[:, 6:] = 0.0
    m_ref, v_ref = gpa.reference_predict(a, x)
    m_fl, v_fl = gpa.flight_predict(fl, x[:, :3], x[:, 3:6])
    assert np.max(np.abs(m_fl - m_ref)) <= 1e-5 * np.max(np.abs(m_ref))
    assert np.max(np.abs(v_fl - v_ref)) <= 1e-4 * a.outputscale * np.max(a.output_scale ** 2)


def test_conditioning_recorded(artifact):
    c = json.loads(artifact.to_json())["payload"]["conditioning"]
    K = gpa.kernel_zz(artifact.arrays.Z, artifact.arrays.lengthscale, 0.9) + 1e-6 * np.eye(M)
    assert math.isclose(float.fromhex(c["cond"]), np.linalg.cond(K), rel_tol=1e-9)
    assert float.fromhex(c["cond_max"]) == 1e6


def _set(doc, path, value):
    node = doc
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = value
    return doc


@pytest.mark.parametrize("edit, match", [
    (lambda d: _set(d, ["format"], "staregen.mlp-artifact"), "format: expected 'staregen.gp-artifact'"),
    (lambda d: _set(d, ["version"], 2), "version: unsupported artifact version"),
    (lambda d: reseal(_set(d, ["payload", "hyper", "jitter"], "0x1.zzp-20")), "payload.hyper.jitter: "),
    (lambda d: reseal(_set(d, ["payload", "hyper", "outputscale"], 0.9)), "expected a hex-float string"),
    (lambda d: reseal(_set(d, ["payload", "inducing", "Z"], d["payload"]["inducing"]["Z"][:-1])),
     "payload.inducing.Z: shape mismatch"),
    (lambda d: reseal(_set(d, ["payload", "variational", "R"], [r[:-1] for r in d["payload"]["variational"]["R"]])),
     "payload.variational.R[0]: shape mismatch"),
    (lambda d: reseal(_set(d, ["payload", "flight", "g"], d["payload"]["flight"]["g"] + ["0x1p+0"])),
     "payload.flight.g: shape mismatch"),
    (lambda d: reseal(_set(d, ["payload", "hyper", "lengthscale", 2], "nan")), "payload.hyper.lengthscale[2]: must be finite"),
    (lambda d: reseal(_set(d, ["payload", "hyper", "noise", 0], "-0x1p-4")), "payload.hyper.noise: every value must be > 0"),
    (lambda d: reseal(_set(d, ["payload", "hyper", "jitter"], hex_float(0.5))), "payload.hyper.jitter: must be in [0, 0.01]"),
    (lambda d: reseal(_set(d, ["payload", "flight", "kxx"], "0x1.000002p+0")), "payload.flight.kxx: differs by more than 1 float32 ulp"),
    (lambda d: reseal(_set(d, ["payload", "conditioning", "cond"], hex_float(12.0))), "payload.conditioning.cond: recorded 12"),
    (lambda d: reseal(_set(d, ["payload", "conditioning", "cond_max"], hex_float(1.0))), "exceeds cond_max 1 "),
    (lambda d: reseal(_set(d, ["payload", "surprise"], 1)), "payload.surprise: unknown field"),
    (lambda d: _set(d, ["payload", "metadata", "seed"], 7), "sha256: mismatch"),
    (lambda d: _set(d, ["sha256"], "abc"), "sha256: expected 64 lowercase hex digits"),
])
def test_malformed_refused_in_one_line(tmp_path, artifact, edit, match):
    refused(edit(json.loads(artifact.to_json())), match, tmp_path)


def test_duplicate_inducing_points_refused(tmp_path):
    doc = json.loads(make().to_json())
    Z = doc["payload"]["inducing"]["Z"]
    Z[1] = list(Z[0])
    refused(reseal(doc), "payload.conditioning.cond: condition number", tmp_path)


def test_flight_value_tampered_refused(tmp_path, artifact):
    doc = json.loads(artifact.to_json())
    a0 = float.fromhex(doc["payload"]["flight"]["A"][0])
    doc["payload"]["flight"]["A"][0] = hex_float(float(np.float32(a0 * 1.001)))
    refused(reseal(doc), "payload.flight.A: differs", tmp_path)


def test_not_json_and_missing_file(tmp_path):
    p = tmp_path / "x.json"
    p.write_text("{nope")
    with pytest.raises(ArtifactError, match="not valid JSON"):
        gpa.load(p)
    with pytest.raises(ArtifactError, match="no such file"):
        gpa.load(tmp_path / "missing.json")


def test_construction_validates():
    with pytest.raises(ArtifactError, match="payload.variational.m: shape mismatch"):
        make(m=np.zeros((3, M + 1)))
    with pytest.raises(ArtifactError, match="payload.variational.R.0.: diagonal"):
        make(R=np.zeros((3, M, M)))


def plant_unit_folder(tmp_path, monkeypatch, name: str, init_text: str) -> None:
    """A unit folder `name` with the given __init__.py beside codegen/units, the registry reset."""
    (tmp_path / name).mkdir()
    (tmp_path / name / "__init__.py").write_text(init_text)
    monkeypatch.setattr(units, "__path__", [*units.__path__, str(tmp_path)])
    monkeypatch.setattr(units, "_discovered", False)
    monkeypatch.setattr(units, "_registered", {})


def test_a_unit_folder_under_construction_is_skipped(tmp_path, monkeypatch):
    """`KIND = None` keeps a folder out of the registry (a unit whose artifact exists before its C)."""
    plant_unit_folder(tmp_path, monkeypatch, "wip", '"""Under construction."""\nKIND = None\n')
    known = units.kinds()
    assert "wip" not in known and {"gp", "rbf"} <= set(known)


def test_a_unit_folder_without_kind_is_an_error(tmp_path, monkeypatch):
    """A folder that forgets KIND must not vanish from the registry silently."""
    plant_unit_folder(tmp_path, monkeypatch, "nokind", '"""A unit folder that forgot its KIND."""\n')
    with pytest.raises(CodegenError, match="codegen/units/nokind: defines no KIND"):
        units.kinds()
