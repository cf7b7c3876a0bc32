"""`staregen report`: every table and every figure of the evaluation in report.html (parsed), the
same tables in report.md, the paper's numbers beside ours, hostile text escaped."""
from __future__ import annotations

import json
from html.parser import HTMLParser

import numpy as np

from host.cli import main
from host.sim import gp_example
from host.tune import figures
from host.tune import report_documents as documents
from host.tune.report import PAPER_TABLE9, _g


class Collect(HTMLParser):
    def __init__(self):
        super().__init__()
        self.tables, self.imgs, self.cells, self._in = 0, [], [], None

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables += 1
        if tag == "img":
            self.imgs.append(dict(attrs))
        if tag in ("td", "th"):
            self._in = tag

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self._in = None

    def handle_data(self, data):
        if self._in:
            self.cells.append(data)


def _evaluation(label_hostile: str) -> dict:
    def row(j):
        return {"J_A": j, "J_w": j / 5, "J": 2 * j, "targets": 3, "per_target": {"J_A": [j] * 3, "J_w": [j / 5] * 3}}
    staring = {"PID (Table 1)": row(5e-4), "PID (tuned)": row(4e-4), "NN (float64)": row(3e-4), label_hostile: row(6e-4)}
    t = list(np.arange(25.0, 60.0, 0.1))
    resp = [[-0.005 * (1 - np.exp(-max(x - 30, 0) / 2))] * 3 for x in t]
    step = {k: {"mean": {"overshoot_pct": [1, 2, 3], "settling_s": [4, 5, 6], "steady_state_deg": [1e-5, 2e-5, 3e-5]},
                "targets": 1, "first_target_response_deg": resp, "t": t} for k in staring}
    freq = {k: {"freqs_hz": [0.1, 1.0, 3.0], "amplitude_deg": [[1e-3, 1e-4, 1e-5]] * 3} for k in staring}
    return {"staring": staring, "staring_central": staring, "step": step, "frequency": freq,
            "impulse": {"t_pid_first_s": 30.0, "t_nn_back_s": 41.2, "peak_A_bd_deg": 0.3, "final_max_A_bd_deg": 1e-3},
            "timing": {"staring_s": 1.0}}


def test_report_holds_every_table_and_figure(tmp_path):
    ev = tmp_path / "ev"
    ev.mkdir()
    hostile = "<script>alert(1)</script> | PD+FF"
    doc = _evaluation(hostile)
    (ev / "evaluate.json").write_text(json.dumps(doc))
    figures.fig10_scatter(doc["staring"], ev / "fig10_scatter.png")
    figures.fig11_12_step(doc["step"], ev / "fig11_12_step.png")
    figures.fig13_14_frequency(doc["frequency"], ev / "fig13_14_frequency.png")
    tune = tmp_path / "tune"
    tune.mkdir()
    (tune / "result.json").write_text(json.dumps({
        "grid": "coarse", "triples": 60, "targets": 3, "duration": 20.0, "timing": {"wall_seconds": 3.0},
        "best": {a: {"kp": 17.0, "ki": 0.0, "kd": 46.0, "objective": 1e-4, "table1_on_grid": True,
                     "table1_objective": 2e-4} for a in "xyz"},
        "check": {"table1": {"J": 1e-3}, "tuned": {"J": 8e-4}, "ratio_tuned_to_table1": 0.8}}))
    assert main(["report", "--evaluate", str(ev), "--tune", str(tune), "--out", str(tmp_path / "r")]) == 0
    text = (tmp_path / "r" / "report.html").read_text()
    p = Collect()
    p.feed(text)
    # tuning, Table 8, Table 9, step, frequency
    assert p.tables == 5
    assert len(p.imgs) == 3 and all(i["src"].startswith("data:image/png;base64,") for i in p.imgs)
    assert "<script>" not in text and "&lt;script&gt;" in text
    assert f"{PAPER_TABLE9['NN'][2]:.3g}" in p.cells and f"{PAPER_TABLE9['PID'][2]:.3g}" in p.cells
    md = (tmp_path / "r" / "report.md").read_text()
    assert md.count("\n|---|") == 5 and md.count("![") == 3
    assert all((tmp_path / "r" / n).is_file() for n in ("fig10_scatter.png", "fig11_12_step.png", "fig13_14_frequency.png"))
    assert "Reading: NN / best PID" in md


def test_bad_inputs(tmp_path, capsys):
    assert main(["report", "--evaluate", str(tmp_path / "none"), "--out", str(tmp_path / "r")]) == 2
    assert "not a folder" in capsys.readouterr().err
    (tmp_path / "ev").mkdir()
    (tmp_path / "ev" / "evaluate.json").write_text("{")
    assert main(["report", "--evaluate", str(tmp_path / "ev"), "--out", str(tmp_path / "r")]) == 2
    assert "not valid JSON" in capsys.readouterr().err
    (tmp_path / "ev" / "evaluate.json").write_text("{}")
    assert main(["report", "--evaluate", str(tmp_path / "ev"), "--out", str(tmp_path / "r")]) == 2
    assert "not written by" in capsys.readouterr().err


def test_report_of_a_real_evaluation_holds_every_table_and_figure(tmp_path, artifact_file):
    """The path a user runs: `staregen evaluate` (small) then `staregen report`; the HTML parsed."""
    ev, out = tmp_path / "ev", tmp_path / "r"
    assert main(["evaluate", "--network", artifact_file, "--controllers", "pid,nn", "--targets", "central",
                 "--duration", "12", "--response-targets", "1", "--freqs", "1", "--workers", "1",
                 "--no-progress", "--out", str(ev)]) == 0
    assert main(["report", "--evaluate", str(ev), "--out", str(out)]) == 0
    text = (out / "report.html").read_text()
    p = Collect()
    p.feed(text)
    # Table 8 (central), Table 9 (targets), step, frequency; no tuning table without --tune
    assert p.tables == 4
    figs = ("fig10_scatter.png", "fig11_12_step.png", "fig13_14_frequency.png", "fig15_impulse.png")
    assert len(p.imgs) == len(figs) and all(i["src"].startswith("data:image/png;base64,") for i in p.imgs)
    assert all((out / n).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for n in figs)
    evaluation = json.loads((ev / "evaluate.json").read_text())
    for label, row in evaluation["staring"].items():
        assert label in p.cells and _g(row["J"]) in p.cells
    md = (out / "report.md").read_text()
    assert md.count("\n|---|") == 4 and md.count("![") == len(figs)
    assert "Evaluation plan: 1 staring targets × 12 s" in md and "A reduced run" in md


def _calibration(hostile: str) -> dict:
    pid = {w: {"J_A": 5e-4, "J_w": 5e-5, "J": 7.5e-4} for w in ("central", "all")}
    nn = {w: {"J_A": 3e-4, "J_w": 4e-5, "J": 5e-4} for w in ("central", "all")}
    mean = {"overshoot_pct": [1, 2, 3], "settling_s": [4, 5, 6], "steady_state_deg": [1e-5, 2e-5, 3e-5]}
    return {"labels": {"table1": "PID (Table 1)", "tuned": None, "network": "NN (float64)"},
            "candidates": [{"reading": hostile, "residual": 0.25, "pid": pid,
                            "ratios": {"central J_A": 1.26, "central J_w": 1.18, "all J_A": 1.26, "all J_w": 1.18}}],
            "chosen": hostile, "chosen_scenario": {"reading": hostile, "sha256": "ab" * 32},
            "prediction": {"staring": {"PID (Table 1)": pid, "NN (float64)": nn},
                           "step": {"PID (Table 1)": mean, "NN (float64)": mean}},
            "nn_to_pid_ratio": {"PID (Table 1)": 0.6667}, "paper_nn_to_pid_ratio": 0.658}


def test_the_fidelity_section_holds_the_calibration_escaped(tmp_path):
    ev, cal = tmp_path / "ev", tmp_path / "cal"
    ev.mkdir()
    cal.mkdir()
    doc = _evaluation("PD+FF")
    doc["plan"] = {"targets": 100, "duration": 100.0, "response_targets": 100, "freqs_hz": [1.0], "seed": 0,
                   "error_reading": "table6", "preset": "paper"}
    doc["scenario"] = {"reading": "table6", "sha256": "cd" * 32}
    (ev / "evaluate.json").write_text(json.dumps(doc))
    hostile = "<img src=x onerror=alert(1)>|x"
    (cal / "calibration.json").write_text(json.dumps(_calibration(hostile)))
    assert main(["report", "--evaluate", str(ev), "--calibration", str(cal), "--out", str(tmp_path / "r")]) == 0
    md = (tmp_path / "r" / "report.md").read_text()
    assert "## Fidelity to paper 001" in md and "Chosen reading:" in md
    assert "predicted NN / PID (Table 1) J̄ over the targets = 0.67" in md and "(paper 0.66)" in md
    assert md.count("scenario table6 (sha256 cdcdcdcdcdcdcdcd…)") == 4       # Tables 8, 9, step, frequency
    assert "<img" not in md and "&lt;img src=x onerror=alert(1)&gt;" in md
    text = (tmp_path / "r" / "report.html").read_text()
    assert "<img src=x" not in text and "&lt;img src=x onerror=alert(1)&gt;" in text
    p = Collect()
    p.feed(text)
    assert "5e-04" not in p.cells and _g(5e-4) in p.cells and _g(PAPER_TABLE9["NN"][2]) in p.cells
    (cal / "calibration.json").write_text("{}")
    assert main(["report", "--evaluate", str(ev), "--calibration", str(cal), "--out", str(tmp_path / "r2")]) == 2


RBF_METRICS = {"controller": "rbf-c", "theorem": 2, "period": 0.1, "duration": 1000.0, "t_rho_5m": 28.6,
               "t_rho_1m": 36.0, "t_attitude_1deg": [5.4, 3.3, 2.7], "delta_v": 306.0, "torque_impulse": 17.2,
               "min_rho": 51.7, "weight_bound_active_steps": 12, "rms_e1": [5.1e-5, 1e-6, 7e-7, 4e-6, 1e-5, 3e-6],
               "golden_mismatch_steps": 0, "max_rho_diff_m": 1.2e-4, "max_attitude_diff_deg": 2.1e-3}


def _rbf_run(folder, **changes):
    folder.mkdir()
    (folder / "metrics.json").write_text(json.dumps({**RBF_METRICS, **changes}))
    return folder


def test_the_rbf_section_puts_paper_002_beside_each_run(tmp_path):
    run1 = _rbf_run(tmp_path / "sil")
    run2 = _rbf_run(tmp_path / "t1", controller="rbf<script>", theorem=1, t_rho_1m=None,
                    t_attitude_1deg=[5.5, None, 2.8])
    (run1 / "fig_range_los.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"0" * 16)
    assert main(["report", "--rbf", str(run1), "--rbf", str(run2), "--out", str(tmp_path / "r")]) == 0
    md = (tmp_path / "r" / "report.md").read_text()
    assert "| paper 002 (§3.2) | 1, 2 | \\- | 22.9 | \\- | 5.7 |" in md
    assert "| rbf-c | 2 | 0.1 | 28.6 | 36.0 | 5.4 | 306 |" in md
    assert "0 mismatching steps; \\|Δρ\\| ≤ 0.00012 m" in md
    assert "| 1 | 0.1 | 28.6 | not reached | not reached |" in md      # a None time is not a number
    page = Collect()
    page.feed((tmp_path / "r" / "report.html").read_text())
    assert "rbf<script>" in page.cells and len(page.imgs) == 1       # escaped text, the one figure
    assert (tmp_path / "r" / "rbf1_fig_range_los.png").exists()
    assert "evaluation wall times" not in md


def test_bad_rbf_inputs_are_one_line(tmp_path, capsys):
    assert main(["report", "--out", str(tmp_path / "r")]) == 2
    assert "give --evaluate DIR, --rbf DIR, --gp DIR, --basilisk DIR or several" in capsys.readouterr().err
    assert main(["report", "--rbf", str(tmp_path / "none"), "--out", str(tmp_path / "r")]) == 2
    assert "--rbf" in capsys.readouterr().err
    bad = _rbf_run(tmp_path / "bad", t_rho_5m="soon")
    assert main(["report", "--rbf", str(bad), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "not written by `staregen simulate --controller rbf`" in err and "t_rho_5m" in err and err.count("\n") == 1
    partial = {k: v for k, v in RBF_METRICS.items() if k != "max_rho_diff_m"}
    (tmp_path / "partial").mkdir()
    (tmp_path / "partial" / "metrics.json").write_text(json.dumps(partial))
    assert main(["report", "--rbf", str(tmp_path / "partial"), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "max_rho_diff_m: missing" in err and err.count("\n") == 1 and "Traceback" not in err
    good = _rbf_run(tmp_path / "good")
    assert main(["report", "--rbf", str(good), "--tune", str(good), "--out", str(tmp_path / "r")]) == 2
    assert "--tune and --calibration need --evaluate" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


# ----------------------------------------------------------------------------- paper 004 (--gp)

GP_METRICS = {"controller": "gp", "start": "capture", "duration": 600.0, "n_inducing": 20, "t_settle_1deg": 150.2,
              "t_settle_0p1deg": 330.0, "steady_error_deg_mean": 0.012, "steady_error_deg_max": 0.02,
              "torque_rms": [0.14, 0.25, 0.22], "max_abs_torque": 1.0, "h_w_end": [38.0, -40.7, 45.2],
              "t_momentum_limit": [None, 824.0, 686.0], "gains_first_60s": [4.2, 73.1], "gains_last_60s": [4.01, 72.05],
              "var_fraction_first_60s": 0.017, "var_fraction_last_60s": 0.001}
BASE_METRICS = {**GP_METRICS, "controller": "gp-baseline", "t_settle_1deg": None, "t_settle_0p1deg": None,
                "steady_error_deg_mean": 2.215, "steady_error_deg_max": 2.3, "gains_first_60s": [4.0, 72.0],
                "gains_last_60s": [4.0, 72.0], "var_fraction_first_60s": None, "var_fraction_last_60s": None}


def _gp_run(folder, base=GP_METRICS, **changes):
    folder.mkdir()
    (folder / "metrics.json").write_text(json.dumps({**base, **changes}))
    return folder


def test_the_gp_section_puts_baseline_and_gp_law_beside_the_papers_claims(tmp_path):
    runs = [_gp_run(tmp_path / "b", BASE_METRICS), _gp_run(tmp_path / "g"),
            _gp_run(tmp_path / "go", start="outside", var_fraction_first_60s=0.13, gains_first_60s=[5.5, 81.0],
                    law={"k1": 4.0, "k1_bar": 16.0}),
            _gp_run(tmp_path / "bo", BASE_METRICS, start="outside", steady_error_deg_mean=0.001, t_settle_1deg=90.0)]
    (runs[1] / "fig7_variance_gains.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"0" * 16)
    argv = ["report", "--out", str(tmp_path / "r")]
    for r in runs:
        argv += ["--gp", str(r)]
    assert main(argv) == 0
    md = (tmp_path / "r" / "report.md").read_text()
    assert "Paper 004" in md
    assert "| gp-baseline | capture | \\- | not reached | not reached | 2.21 / 2.3 |" in md
    assert "| gp | capture | 20 | 150.2 | 330.0 | 0.012 / 0.02 | 0.140, 0.250, 0.220 | 1.000 |" in md
    assert "| 686 | 0.017 / 0.001 | 4.20 / 4.01 | 73.1 / 72.0 |" in md       # earliest axis to 50 N·m·s
    assert "Ours, start capture: holds — within 1° from 150.2 s vs not reached;" in md
    assert "Ours, start outside: does not hold" in md                     # the baseline settled sooner there
    assert "Ours, holds — first 60 s: variance fraction s 0.13 (outside) vs 0.017 (capture), K1 5.50 vs 4.20 N·m " \
           "(bounds 4-16)" in md
    assert (tmp_path / "r" / "gp2_fig7_variance_gains.png").exists()
    assert "run 2 (gp, start capture): normalised variance and gains (Fig. 7)" in md


def test_bad_gp_inputs_are_one_line(tmp_path, capsys):
    assert main(["report", "--gp", str(tmp_path / "none"), "--out", str(tmp_path / "r")]) == 2
    assert "--gp" in capsys.readouterr().err
    bad = _gp_run(tmp_path / "bad", start=3)
    assert main(["report", "--gp", str(bad), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "not written by `staregen simulate --controller gp-baseline|gp|gp-c|gp-arm`" in err and "start" in err
    assert err.count("\n") == 1 and not (tmp_path / "r").exists()
    for i, change in enumerate([{"controller": "gp-x"}, {"start": "far"}, {"var_fraction_first_60s": None}]):
        odd = _gp_run(tmp_path / f"odd{i}", **change)
        assert main(["report", "--gp", str(odd), "--out", str(tmp_path / "r")]) == 2
        assert next(iter(change)) in capsys.readouterr().err
    half = _gp_run(tmp_path / "half", controller="gp-c", golden_mismatch_steps=0)    # a C run without its comparison
    assert main(["report", "--gp", str(half), "--out", str(tmp_path / "r")]) == 2
    assert "mode: missing (a C-in-the-loop run has all of" in capsys.readouterr().err


def test_the_gp_section_reports_the_generated_c_in_the_loop(tmp_path):
    c_run = _gp_run(tmp_path / "c", controller="gp-arm", mode="PIL ARM emulator", golden_mismatch_steps=0,
                    max_angle_diff_deg=3.5e-6, max_torque_diff=1.6e-5, max_mu_diff=1.2e-5, cycles_median=8613,
                    cycles_max=8615)
    assert main(["report", "--gp", str(_gp_run(tmp_path / "g")), "--gp", str(c_run), "--out", str(tmp_path / "r")]) == 0
    md = (tmp_path / "r" / "report.md").read_text()
    assert ("Generated C in the loop, gp-arm (PIL ARM emulator, start capture): 0 steps differ from the golden model; "
            "against the float64 law \\|Δ angle\\| ≤ 3.50e-06°") in md
    assert "cycles per step (ideal) median 8613, max 8615." in md


def test_the_report_knows_the_names_the_gp_runs_write():
    assert documents.GP_CONTROLLERS == gp_example.CONTROLLERS and documents.GP_STARTS == gp_example.STARTS
