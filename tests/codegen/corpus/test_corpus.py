"""The malformed-input corpus: every file gives exactly its expected one-line error (artifacts
through codegen.artifact.load and `staregen artifact check`, parameter files through load_params)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from codegen import artifact as art
from codegen.units.tanh.params import TanhParamsError, load_params
from host.cli import main

HERE = Path(__file__).resolve().parent
EXPECTED = json.loads((HERE / "expected.json").read_text())


def test_corpus_is_large_enough():
    assert len(EXPECTED) >= 40
    assert sorted(EXPECTED) == sorted(p.relative_to(HERE).as_posix() for p in HERE.glob("*/*") if p.is_file())


@pytest.mark.parametrize("rel", sorted(k for k in EXPECTED if k.startswith("artifacts/")))
def test_artifact_corpus(rel, capsys):
    path = HERE / rel
    with pytest.raises(art.ArtifactError) as exc:
        art.load(path)
    text = str(exc.value)
    assert "\n" not in text and text.startswith(str(path)) and EXPECTED[rel] in text, text
    assert main(["artifact", "check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and EXPECTED[rel] in err and "Traceback" not in err


@pytest.mark.parametrize("rel", sorted(k for k in EXPECTED if k.startswith("params/")))
def test_params_corpus(rel):
    with pytest.raises(TanhParamsError) as exc:
        load_params(HERE / rel)
    assert "\n" not in str(exc.value) and EXPECTED[rel] in str(exc.value), str(exc.value)
