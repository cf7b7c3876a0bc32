"""Issue 25 (defects 12, 15): `staregen report` checks every document it reads against the shape it
uses (one line naming the file and the field, nothing written), writes every text from a file or
the command line as literal Markdown, and embeds a figure only from a regular PNG file."""
from __future__ import annotations

import copy
import json
import os
import re

import pytest

from host.cli import main
from host.tune import figures

ROW = {"J_A": 4e-4, "J_w": 8e-5, "J": 6e-4, "targets": 1}
MEAN = {"overshoot_pct": [1, 2, 3], "settling_s": [4, 5, 6], "steady_state_deg": [1e-5, 2e-5, 3e-5]}
LABELS = ("PID (Table 1)", "NN (float64)")


def evaluation(labels=LABELS) -> dict:
    return {"staring": {k: dict(ROW) for k in labels}, "staring_central": {k: dict(ROW) for k in labels},
            "step": {k: {"mean": copy.deepcopy(MEAN)} for k in labels},
            "frequency": {k: {"freqs_hz": [0.1, 1.0], "amplitude_deg": [[1e-3, 1e-4]] * 3} for k in labels},
            "plan": {"targets": 1, "duration": 12.0, "response_targets": 1, "freqs_hz": [0.1, 1.0], "seed": 0,
                     "preset": "paper", "error_reading": "table6"},
            "timing": {"staring_s": 1.0}}


def tuning(grid_name="coarse") -> dict:
    return {"grid": grid_name, "triples": 60, "targets": 3, "duration": 20.0, "timing": {"wall_seconds": 3.0},
            "best": {a: {"kp": 17.0, "ki": 0.0, "kd": 46.0, "objective": 1e-4, "table1_on_grid": True,
                         "table1_objective": 2e-4} for a in "xyz"},
            "check": {"table1": {"J": 1e-3}, "tuned": {"J": 8e-4}, "ratio_tuned_to_table1": 0.8}}


def folder(tmp_path, name: str, file: str, doc) -> str:
    path = tmp_path / name
    path.mkdir()
    (path / file).write_text(doc if isinstance(doc, str) else json.dumps(doc))
    return str(path)


def run_report(capsys, *argv) -> tuple[int, str]:
    code = main(["report", *argv])
    return code, capsys.readouterr().err


def _edit(doc: dict, path: str, value) -> dict:
    """A copy of `doc` with the field at the dotted `path` set to `value`."""
    out = copy.deepcopy(doc)
    *parents, last = path.split(".")
    node = out
    for p in parents:
        node = node[p]
    node[last] = value
    return out


BAD_EVALUATIONS = [
    ({"staring": [], "step": {}, "frequency": {}}, "staring: must be an object"),
    (_edit(evaluation(), "staring.PID (Table 1)", {}), "staring['PID (Table 1)'].J_A: missing"),
    (_edit(evaluation(), "plan.duration", "b"), "plan.duration: must be a number > 0, got 'b'"),
    (_edit(evaluation(), "staring.PID (Table 1).J", 0), "staring['PID (Table 1)'].J: must be a number > 0"),
    (_edit(evaluation(), "staring.NN (float64).J_w", None), "J_w: must be a number >= 0"),
    (_edit(evaluation(), "step.NN (float64).mean.settling_s", [1, 2]), "settling_s: must be a list of 3 values"),
    (_edit(evaluation(), "frequency.NN (float64).amplitude_deg", [[1.0]] * 3), "must hold 2 frequencies"),
    (_edit(evaluation(), "scenario", []), "scenario: must be an object"),
    (_edit(evaluation(), "impulse", {"t_pid_first_s": 30.0}), "impulse.t_nn_back_s: missing"),
    ('{"staring": {"PID (Table 1)": {"J_A": NaN}}}', "not valid JSON"),
    ("[]", "the document: must be an object"),
]


@pytest.mark.parametrize("doc, message", BAD_EVALUATIONS, ids=[m for _, m in BAD_EVALUATIONS])
def test_a_malformed_evaluation_is_one_line_naming_the_field(tmp_path, capsys, doc, message):
    ev = folder(tmp_path, "ev", "evaluate.json", doc)
    code, err = run_report(capsys, "--evaluate", ev, "--out", str(tmp_path / "r"))
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith("staregen report: error: ") and "evaluate.json" in err and message in err, err
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize("doc, message", [
    ({"best": 5}, "grid: missing"),
    (_edit(tuning(), "best", 5), "best: must be an object"),
    (_edit(tuning(), "check.table1.J", 0), "check.table1.J: must be a number > 0"),
    (_edit(tuning(), "best.x.table1_on_grid", "yes"), "best['x'].table1_on_grid: must be true or false"),
    (_edit(tuning(), "timing", [1]), "timing: must be an object"),
])
def test_a_malformed_tuning_result_is_one_line_naming_the_field(tmp_path, capsys, doc, message):
    ev = folder(tmp_path, "ev", "evaluate.json", evaluation())
    tune = folder(tmp_path, "tune", "result.json", doc)
    code, err = run_report(capsys, "--evaluate", ev, "--tune", tune, "--out", str(tmp_path / "r"))
    assert code == 2 and err.count("\n") == 1, err
    assert "result.json: not written by `staregen tune pid`: " in err and message in err, err
    assert not (tmp_path / "r").exists()


PAIR = {w: dict(ROW) for w in ("central", "all")}
CALIBRATION = {"labels": {"table1": "PID (Table 1)", "tuned": None, "network": "NN (float64)"},
               "candidates": [{"reading": "table6", "residual": 0.2, "ratios": {"central J_A": 1.0}}],
               "chosen": "table6", "prediction": {"staring": {"PID (Table 1)": PAIR, "NN (float64)": PAIR}},
               "nn_to_pid_ratio": {}, "paper_nn_to_pid_ratio": 0.658}


@pytest.mark.parametrize("edit, message", [
    (("prediction.staring", {"PID (Table 1)": PAIR}), "no row for labels.network 'NN (float64)'"),
    (("candidates", []), "candidates: must be a list of values (at least 1)"),
    (("step_model", {"laws": {}}), "step_model.critically_damped_for_paper_nn_settling: missing"),
    (("paper_nn_to_pid_ratio", "0.658"), "paper_nn_to_pid_ratio: must be a number > 0"),
])
def test_a_malformed_calibration_is_one_line_naming_the_field(tmp_path, capsys, edit, message):
    ev = folder(tmp_path, "ev", "evaluate.json", evaluation())
    cal_dir = folder(tmp_path, "cal", "calibration.json", _edit(CALIBRATION, *edit))
    code, err = run_report(capsys, "--evaluate", ev, "--calibration", cal_dir, "--out", str(tmp_path / "r"))
    assert code == 2 and err.count("\n") == 1 and "calibration.json: not written by `staregen calibrate`" in err, err
    assert message in err, err
    assert not (tmp_path / "r").exists()


def test_a_well_formed_calibration_is_reported(tmp_path, capsys):
    ev = folder(tmp_path, "ev", "evaluate.json", evaluation())
    cal_dir = folder(tmp_path, "cal", "calibration.json", CALIBRATION)
    code, err = run_report(capsys, "--evaluate", ev, "--calibration", cal_dir, "--out", str(tmp_path / "r"))
    assert code == 0, err
    assert "## Fidelity to paper 001" in (tmp_path / "r" / "report.md").read_text()


HOSTILE = "x\n## injected <script>alert(1)</script> [link](javascript:alert(1)) *bold* `code`"


def test_labels_grid_and_commands_are_literal_markdown(tmp_path, capsys):
    ev = folder(tmp_path, "ev", "evaluate.json", evaluation(LABELS + (HOSTILE,)))
    tune = folder(tmp_path, "tune", "result.json", tuning(grid_name=HOSTILE))
    code, err = run_report(capsys, "--evaluate", ev, "--tune", tune, "--command", HOSTILE, "--command",
                           "staregen evaluate\n# heading", "--out", str(tmp_path / "r"))
    assert code == 0, err
    md = (tmp_path / "r" / "report.md").read_text()
    assert not any(ln.lstrip().startswith(("## injected", "# heading")) for ln in md.splitlines())   # no new block
    assert "<script" not in md and not re.search(r"(?<!\\)\]\(javascript:", md) and "`code`" not in md
    literal = ("x ## injected &lt;script&gt;alert(1)&lt;/script&gt; \\[link\\](javascript:alert(1)) \\*bold\\* "
               "\\`code\\`")
    assert md.count(literal) >= 4 and "staregen evaluate # heading" in md    # label rows, grid, command
    html = (tmp_path / "r" / "report.html").read_text()
    assert "<script" not in html and "&lt;script&gt;" in html


def test_the_command_flag_does_not_replace_the_subcommand_in_errors(tmp_path, capsys):
    code, err = run_report(capsys, "--command", "staregen evaluate", "--evaluate", str(tmp_path / "none"),
                           "--out", str(tmp_path / "r"))
    assert code == 2 and err.startswith("staregen report: error: --evaluate"), err


@pytest.mark.parametrize("make", ["symlink", "text", "fifo"])
def test_a_figure_that_is_not_a_regular_png_file_is_not_embedded(tmp_path, capsys, make):
    ev = folder(tmp_path, "ev", "evaluate.json", evaluation())
    figures.fig13_14_frequency(evaluation()["frequency"], tmp_path / "ev" / "fig13_14_frequency.png")
    fig = tmp_path / "ev" / "fig10_scatter.png"
    if make == "symlink":
        (tmp_path / "real.png").write_bytes((tmp_path / "ev" / "fig13_14_frequency.png").read_bytes())
        os.symlink(tmp_path / "real.png", fig)      # a PNG behind the link: still refused, a link may point anywhere
    elif make == "text":
        fig.write_text("root:x:0:0:root:/root:/bin/bash\n")
    else:
        os.mkfifo(fig)
    code, err = run_report(capsys, "--evaluate", ev, "--out", str(tmp_path / "r"))
    assert code == 2 and err.count("\n") == 1 and "fig10_scatter.png: not embedded" in err, err
    assert not (tmp_path / "r").exists()


def test_a_regular_png_figure_is_embedded(tmp_path, capsys):
    ev = folder(tmp_path, "ev", "evaluate.json", evaluation())
    figures.fig13_14_frequency(evaluation()["frequency"], tmp_path / "ev" / "fig13_14_frequency.png")
    code, err = run_report(capsys, "--evaluate", ev, "--out", str(tmp_path / "r"))
    assert code == 0, err
    html = (tmp_path / "r" / "report.html").read_text()
    assert html.count("data:image/png;base64,") == 1
    copied, source = tmp_path / "r" / "fig13_14_frequency.png", tmp_path / "ev" / "fig13_14_frequency.png"
    assert copied.read_bytes() == source.read_bytes()
