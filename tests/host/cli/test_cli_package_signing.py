"""Issue 25 defect 6: the manifest's seal catches accidents only (anyone re-seals an edited
package); `generate --sign-key` signs it with HMAC-SHA256 and `package check --verify-key` checks
the signature: a re-sealed edit passes the plain check and fails the keyed one."""
from __future__ import annotations

import hashlib
import json
import os
import re

import pytest

from codegen.package import manifest
from tests.host.cli.package_inputs import cli, package_inputs

SMALL = ["--gate-vectors", "100", "--vectors", "8", "--cycles-per-class", "1"]


@pytest.fixture()
def inputs(tmp_path):
    return package_inputs(tmp_path)


def reseal(folder, edit=None, drop_signature=False) -> None:
    """What anyone can do without the key: edit a file, recompute its sha256 and the seal."""
    doc = json.loads((folder / "manifest.json").read_text())
    if edit is not None:
        rel, pattern, new = edit
        text, n = re.subn(pattern, new, (folder / rel).read_text(), count=1)
        assert n == 1
        (folder / rel).write_text(text)
        doc["files"][rel] = hashlib.sha256((folder / rel).read_bytes()).hexdigest()
    if drop_signature:
        del doc["signature"]
    doc["sha256"] = manifest.seal_of(doc)
    (folder / "manifest.json").write_text(manifest.to_text(doc))


def test_signed_package_verifies_and_a_resealed_edit_does_not(tmp_path, capsys, inputs):
    cfg, net = inputs
    key, other = tmp_path / "sign.key", tmp_path / "other.key"
    key.write_bytes(os.urandom(32))
    other.write_bytes(os.urandom(32))
    pkg = tmp_path / "pkg"
    code, _, err = cli(capsys, "generate", "--config", cfg, "--network", net, "--out", pkg, "--sign-key", key, *SMALL)
    assert code == 0, err
    doc = json.loads((pkg / "manifest.json").read_text())
    assert doc["signature"]["algorithm"] == "HMAC-SHA256" and key.read_bytes().hex() not in json.dumps(doc)
    assert "This manifest is also signed" in (pkg / "ICD.md").read_text()

    code, out, _ = cli(capsys, "package", "check", pkg, "--verify-key", key)
    assert code == 0 and "match the manifest" in out and "signature verified" in out
    code, out, _ = cli(capsys, "package", "check", pkg, "--verify-key", other)
    assert code == 1 and out == f"{pkg}: signature: does not verify with this key (a file was edited and " \
                                "re-sealed, or another key signed it)\n"

    # a changed torque limit, re-hashed and re-sealed: the plain check passes, the keyed one does not
    reseal(pkg, ("src/stare.c", r"#define STARE_LIMIT_BITS 0x[0-9a-f]+u", "#define STARE_LIMIT_BITS 0x7f000000u"))
    code, out, _ = cli(capsys, "package", "check", pkg)
    assert code == 0 and "match the manifest" in out
    code, out, _ = cli(capsys, "package", "check", pkg, "--verify-key", key, "--run", "x86")
    assert code == 1 and out.count("\n") == 1 and "signature: does not verify" in out

    # the signature removed and the manifest re-sealed: unsigned, refused under a key
    reseal(pkg, drop_signature=True)
    code, out, _ = cli(capsys, "package", "check", pkg, "--verify-key", key)
    assert code == 1 and out == f"{pkg}: signature: the manifest is not signed (generate the package with --sign-key)\n"


def test_key_files_are_validated(tmp_path):
    (tmp_path / "short").write_bytes(b"x" * 31)
    (tmp_path / "long").write_bytes(b"x" * (manifest.KEY_MAX_BYTES + 1))
    (tmp_path / "ok").write_bytes(b"x" * 32)
    assert manifest.load_key(tmp_path / "ok") == b"x" * 32
    with pytest.raises(manifest.PackageError, match="at least 32 bytes, this one has 31"):
        manifest.load_key(tmp_path / "short")
    with pytest.raises(manifest.PackageError, match="larger than 1024 bytes"):
        manifest.load_key(tmp_path / "long")
    os.mkfifo(tmp_path / "fifo")
    with pytest.raises(manifest.PackageError, match="not a regular file"):
        manifest.load_key(tmp_path / "fifo")                    # refused unopened: does not block
    with pytest.raises(manifest.PackageError, match="not a regular file"):
        manifest.load_key("/dev/zero")
