"""A shard bound to its place (shared by the OCP samples and the PID tuning): its JSON sidecar holds
the place fields the plan expects (index, first item, count, seeds or hashes) and the size and
sha256 of its npz; reading checks both, so a swapped, edited, truncated or foreign shard is a
one-line HostError telling what to delete."""
from __future__ import annotations

import hashlib
from pathlib import Path

from codegen import reading
from host.errors import HostError


def read_json(path: Path, what: str) -> dict:
    """A JSON object (capped, strict read: codegen.reading); anything else is one HostError line."""
    try:
        doc = reading.read_json(path)
    except reading.InputFileError as exc:
        raise HostError(f"{path}: unreadable {what} ({str(exc).removeprefix(f'{path}: ')})") from None
    if not isinstance(doc, dict):
        raise HostError(f"{path}: unreadable {what} (expected a JSON object, got {type(doc).__name__})")
    return doc


def check_place(json_path: Path, sidecar: dict, place: dict, index: int, owner: str) -> None:
    """Every place field of the sidecar equals the plan's for shard `index` of this `owner`."""
    for key, want in place.items():
        if sidecar.get(key) != want:
            raise HostError(f"{json_path}: {key} is {str(sidecar.get(key))[:40]}, shard {index} of this {owner} has "
                            f"{str(want)[:40]} (a copied or edited sidecar); delete it and its npz to recompute the shard")


def read_bound_npz(npz_path: Path, json_path: Path, sidecar: dict) -> bytes:
    """The npz's bytes, which must have the size and sha256 its sidecar records."""
    try:
        data = npz_path.read_bytes()
    except OSError:
        raise HostError(f"{npz_path}: missing although its sidecar exists; "
                        f"delete {json_path.name} to recompute it") from None
    if len(data) != sidecar.get("npz_bytes") or hashlib.sha256(data).hexdigest() != sidecar.get("npz_sha256"):
        raise HostError(f"{npz_path}: corrupt or truncated (size/sha256 differ from its sidecar); "
                        f"delete {npz_path.name} and {json_path.name} to recompute it")
    return data
