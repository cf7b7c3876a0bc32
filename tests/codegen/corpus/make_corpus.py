"""Writes the malformed-input corpus (tests/codegen/corpus/{artifacts,params,configs}/) and
expected.json: each file with the one-line error it must produce. Run once when a case is added:
    python -m tests.codegen.corpus.make_corpus
The files are committed; test_corpus.py loads each and compares the error."""
from __future__ import annotations

import copy
import json
from pathlib import Path

from codegen import artifact as art
from codegen.artifact import payload_sha256

HERE = Path(__file__).resolve().parent


def base_doc() -> dict:
    return json.loads(art.random_artifact((3, 4, 2), seed=7).to_json())


def sealed(doc: dict) -> dict:
    doc["sha256"] = payload_sha256(doc["payload"])
    return doc


def edit(path, value, reseal=True):
    def f(doc):
        node = doc
        for k in path[:-1]:
            node = node[k]
        node[path[-1]] = value
        return sealed(doc) if reseal else doc
    return f


P, M, N, E = "payload", ("payload", "metadata"), ("payload", "network"), ("payload", "envelope")
L0 = ("payload", "network", "layers", 0)
IN = ("payload", "normalisation", "input")

# name -> (mutation of the document, or raw text; expected error substring)
ARTIFACTS = {
    "inject_creator_comment": (edit((*M, "creator"), "x */\n#define sg_inline_tanhf(x) (x)\n/*"),
                               "payload.metadata.creator: must be printable ASCII"),
    "inject_creator_close": (edit((*M, "creator"), "a */ int evil; /* b"), "payload.metadata.creator: must not contain '*/'"),
    "inject_creator_open": (edit((*M, "creator"), "a /* b"), "payload.metadata.creator: must not contain '/*'"),
    "inject_source_newline": (edit((*E, "source"), "Table 2\n#include <stdio.h>"), "payload.envelope.source: must be printable ASCII"),
    "trigraph_description": (edit(("payload", "outputs", "descriptions", 0), "torque ??/"),
                             "payload.outputs.descriptions[0]: must not contain '??'"),
    "backslash_unit": (edit((*E, "units", 0), "deg/s\\"), "payload.envelope.units[0]: must not end in a backslash"),
    "non_ascii_unit": (edit((*E, "units", 1), "°/s"), "payload.envelope.units[1]: must be printable ASCII"),
    "long_creator": (edit((*M, "creator"), "x" * 201), "payload.metadata.creator: must be printable ASCII of at most 200"),
    "creator_not_string": (edit((*M, "creator"), ["a"]), "payload.metadata.creator: expected str, got list"),
    "name_not_identifier": (edit((*E, "names", 0), "1x"), "payload.envelope.names[0]: '1x' is not an identifier"),
    "number_plain_decimal": (edit((*IN, "ymin"), "1"), "payload.normalisation.input.ymin: '1' is not in canonical form"),
    "number_exponent": (edit((*IN, "ymin"), "1e30"), "'1e30' is not in canonical form"),
    "number_upper_case": (edit((*IN, "ymin"), "-0X1P+0"), "'-0X1P+0' is not in canonical form: write '-0x1p+0'"),
    "number_spaces": (edit((*IN, "ymin"), " -0x1p+0 "), "' -0x1p+0 ' is not in canonical form"),
    "number_plus_sign": (edit((*IN, "ymax"), "+0x1p+0"), "'+0x1p+0' is not in canonical form: write '0x1p+0'"),
    "number_trailing_zeros": (edit((*IN, "ymax"), "0x1.000p+0"), "'0x1.000p+0' is not in canonical form"),
    "number_overflow": (edit((*IN, "ymax"), "0x1p+9999999999"), "'0x1p+9999999999' is not a hex float within float64"),
    "number_not_hex": (edit((*IN, "ymax"), "one"), "'one' is not a hex float within float64"),
    "number_json_number": (edit((*IN, "ymax"), 1.0), "payload.normalisation.input.ymax: expected a hex-float string"),
    "number_not_float32": (edit((*L0, "bias", 0), "0x1.0000001p+0"), "payload.network.layers[0].bias[0]: 0x1.0000001p+0 is not exactly representable in float32"),
    "weight_infinite": (edit((*L0, "weights", 0, 0), "inf"), "payload.network.layers[0].weights[0][0]: non-finite value inf"),
    "version_float": (edit(("version",), 1.0), "version: unsupported artifact version 1.0"),
    "version_two": (edit(("version",), 2), "version: unsupported artifact version 2"),
    "version_bool": (edit(("version",), True), "version: unsupported artifact version True"),
    "format_wrong": (edit(("format",), "onnx"), "format: expected 'staregen.mlp-artifact'"),
    "unknown_top_field": (edit(("extra",), 1), "extra: unknown field"),
    "unknown_payload_field": (edit((P, "extra"), 1), "payload.extra: unknown field"),
    "missing_bias": (lambda d: sealed(_drop(d, (*L0, "bias"))), "payload.network.layers[0].bias: missing field"),
    "sizes_negative": (edit((*N, "sizes", 1), -4), "payload.network.sizes[1]: expected a positive integer"),
    "sizes_float": (edit((*N, "sizes", 1), 4.0), "payload.network.sizes[1]: expected a positive integer"),
    "activation_relu": (edit((*N, "activations", 0), "relu"), "payload.network.activations: expected ['tansig', 'purelin']"),
    "shape_short_row": (lambda d: sealed(_pop(d, (*L0, "weights", 0))), "payload.network.layers[0].weights[0]: shape mismatch: expected 3 entries, got 2"),
    "seal_stale": (edit((*L0, "bias", 0), "0x1p-1", reseal=False), "sha256: mismatch"),
    "seal_malformed": (edit(("sha256",), "abc", reseal=False), "sha256: expected 64 lowercase hex digits"),
    "envelope_min_above_max": (edit((*E, "min", 0), "0x1p+10"), "payload.envelope.min[0]: envelope min"),
    "dataset_sha_bad": (edit((*M, "dataset_sha256"), "xyz"), "payload.metadata.dataset_sha256: expected 64 lowercase hex digits"),
    "mse_negative": (edit((*M, "test_mse"), -1.0), "payload.metadata.test_mse: must be a finite value >= 0"),
    "duplicate_key": ("dup", "file: not valid JSON: duplicate key 'version'"),
    "deep_nesting": ("deep", "file: not valid JSON: nested deeper than 32 levels"),
    "nan_constant": ("nan", "file: not valid JSON: NaN is not JSON"),
    "truncated": ("trunc", "file: not valid JSON"),
    "not_utf8": ("latin1", "file: cannot read"),
}


def _drop(doc, path):
    node = doc
    for k in path[:-1]:
        node = node[k]
    del node[path[-1]]
    return doc


def _pop(doc, path):
    node = doc
    for k in path:
        node = node[k]
    node.pop()
    return doc


def _raw(kind: str, doc: dict) -> bytes:
    text = json.dumps(doc, indent=1)
    if kind == "dup":
        return text.replace('"version": 1,', '"version": 1,\n "version": 1,', 1).encode()
    if kind == "deep":
        return ("[" * 5000 + "]" * 5000).encode()
    if kind == "nan":
        return text.replace('"test_mse": null', '"test_mse": NaN', 1).encode()
    if kind == "trunc":
        return text[: len(text) // 2].encode()
    return b"\xff\xfe" + text.encode()   # not UTF-8


PARAMS_BASE = (Path(__file__).resolve().parents[3] / "docs" / "tanh_paper000.toml").read_text()

PARAMS = {
    "missing_k1.toml": (lambda t: t.replace("k1 =", "# k1 ="), "missing key 'k1'"),
    "unknown_key.toml": (lambda t: t + "\nk9 = 1.0\n", "unknown key 'k9'"),
    "negative_gain.toml": (lambda t: t.replace("k2 = ", "k2 = -"), "'k2' = -"),
    "gamma_one.toml": (lambda t: _set(t, "gamma", "1.0"), "'gamma' = 1.0 must be in (0, 1)"),
    "inertia_asymmetric.toml": (lambda t: _set(t, "inertia", "[[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]"),
                                "'inertia' must be symmetric"),
    "inertia_indefinite.toml": (lambda t: _set(t, "inertia", "[[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]"),
                                "'inertia' must be positive definite"),
    "string_value.toml": (lambda t: _set(t, "eta", '"0.1"'), "'eta' must be a finite number"),
    "infinite.toml": (lambda t: _set(t, "eta", "inf"), "'eta': must be finite"),
    "duplicate.toml": (lambda t: t + "\nk1 = 1.0\n", "not valid TOML"),
    "bad_syntax.toml": (lambda t: t + "\n= 3\n", "not valid TOML"),
}


def _set(text: str, key: str, value: str) -> str:
    lines = [ln for ln in text.splitlines() if not ln.split("=")[0].strip() == key]
    return "\n".join(lines) + f"\n{key} = {value}\n"


def main() -> None:
    expected = {}
    for sub in ("artifacts", "params"):
        (HERE / sub).mkdir(exist_ok=True)
        for old in (HERE / sub).iterdir():
            old.unlink()
    for name, (mutate, message) in ARTIFACTS.items():
        doc = base_doc()
        data = _raw(mutate, doc) if isinstance(mutate, str) else (json.dumps(mutate(copy.deepcopy(doc)), indent=1) + "\n").encode()
        (HERE / "artifacts" / f"{name}.json").write_bytes(data)
        expected[f"artifacts/{name}.json"] = message
    for name, (mutate, message) in PARAMS.items():
        (HERE / "params" / name).write_text(mutate(PARAMS_BASE))
        expected[f"params/{name}"] = message
    (HERE / "expected.json").write_text(json.dumps(expected, indent=1, sort_keys=True) + "\n")
    print(f"{len(expected)} corpus files")


if __name__ == "__main__":
    main()
