"""Issue 25 defect 16: `--targets central` works with every other flag at its default in evaluate
and calibrate (the step response defaults to all of the targets), and an explicit count above the
number of targets stays a one-line error."""
from __future__ import annotations

import pytest

from codegen.artifact import random_artifact
from host.cli import build_parser, main
from host.cli.args import parse_response_targets
from host.cli.evaluate import build_plan
from host.errors import HostError
from host.plant.error_model import TABLE6_ERRORS
from host.tune import calibrate as cal


def test_evaluate_targets_central_with_the_defaults():
    args = build_parser().parse_args(["evaluate", "--network", "net.json", "--targets", "central", "--out", "e"])
    plan = build_plan(args, TABLE6_ERRORS)
    assert len(plan.targets) == 1 and plan.response_targets == plan.targets


def test_calibrate_targets_central_with_the_defaults(tmp_path, monkeypatch):
    net = tmp_path / "net.json"
    random_artifact((12, 40, 3), seed=1).save(net)
    seen = {}

    def stop(plan, *args, **kwargs):      # the plan, not the flights
        seen["plan"] = plan
        raise HostError("stopped before flying")

    monkeypatch.setattr(cal, "calibrate", stop)
    assert main(["calibrate", "--network", str(net), "--targets", "central", "--out", str(tmp_path / "c")]) == 2
    assert len(seen["plan"].targets) == 1 and seen["plan"].response_targets == 1


def test_response_targets_all_or_a_count_up_to_the_targets():
    assert parse_response_targets("all", 1) == 1 and parse_response_targets(" ALL ", 100) == 100
    assert parse_response_targets("3", 10) == 3
    with pytest.raises(HostError, match="--response-targets must be at most 1, got 10"):
        parse_response_targets("10", 1)
    with pytest.raises(HostError, match="--response-targets must be an integer"):
        parse_response_targets("1_0", 20)
