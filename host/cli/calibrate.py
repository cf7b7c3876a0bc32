"""`staregen calibrate`: fit the reading of Table 6 on paper 001's PID rows, then predict the network's.

  --network FILE     the trained artifact whose rows are predicted (never used in the fit)
  --tuned FILE       a controller.toml from `staregen tune pid` (adds the tuned PID to the prediction)
  --readings LIST    candidate readings (default: every one of `staregen scenario list`)
Writes OUT/calibration.json, calibration.txt, fig_ratio_vs_noise.png and OUT/scenario.toml (the
chosen reading, for `--scenario` of simulate, evaluate and tune). The method: host/tune/calibrate.py.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from codegen import artifact as art
from codegen.package import config as pc
from host.cli.args import parse_int, parse_number, parse_response_targets
from host.cli.tune import parse_targets
from host.control.baselines import load_baselines
from host.errors import HostError
from host.learn.training import baselines_path
from host.sim import scenario_file
from host.sim.targets import central_target
from host.tune import calibrate as cal
from host.tune.evaluate import ControllerSpec, table1_spec, tuned_spec


def register(subparsers) -> None:
    p = subparsers.add_parser("calibrate", help="fit Table 6's reading on the paper's PID rows, predict the network's",
                              description=__doc__.splitlines()[0])
    p.add_argument("--network", required=True, metavar="FILE", help="trained 12-40-3 artifact")
    p.add_argument("--tuned", default=None, metavar="FILE", help="controller.toml with tuned PID gains")
    p.add_argument("--readings", default="all", help="comma-separated candidate readings (default: all)")
    p.add_argument("--targets", default="all", help="all (the 100) or N (the first N)")
    p.add_argument("--duration", default="100", help="staring run length in s (default 100)")
    p.add_argument("--response-targets", default="all", help="step-response targets: all or N (default all)")
    p.add_argument("--scales", default=",".join(f"{s:g}" for s in cal.DEFAULT_SCALES),
                   help="noise scales of the ratio sweep (default 0,0.25,...,1.5)")
    p.add_argument("--seed", default="0", help="noise seed (default 0)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--out", required=True, help="output folder (created)")
    p.set_defaults(func=run)


def parse_readings(text: str) -> tuple[str, ...]:
    if text.strip().lower() == "all":
        return tuple(scenario_file.READINGS)
    names = tuple(n.strip() for n in text.split(",") if n.strip())
    if not names:
        raise HostError("--readings lists no reading")
    return names


def parse_scales(text: str) -> tuple[float, ...]:
    parts = [p for p in text.split(",") if p.strip()]
    if not parts:
        raise HostError("--scales needs at least one scale")
    return tuple(parse_number(p, "--scales", non_negative=True, maximum=10.0) for p in parts)


def run(args: argparse.Namespace) -> int:
    a = art.load(args.network)
    if a.sizes[0] != 12 or a.sizes[-1] != 3:
        raise HostError(f"--network: the network controller needs a 12-input, 3-output network, got {a.shape_text}")
    targets = parse_targets(args.targets)
    n_resp = parse_response_targets(args.response_targets, len(targets))
    c = central_target()
    plan = cal.CalibrationPlan(targets=targets, central=(c.name, c.lon, c.lat, 0), readings=parse_readings(args.readings),
                               duration=parse_number(args.duration, "--duration", minimum=11.0, maximum=86400.0),
                               response_targets=n_resp, scales=parse_scales(args.scales),
                               seed=parse_int(args.seed, "--seed", maximum=2**32 - 1))
    tuned = None
    if args.tuned:
        g = pc.load(args.tuned).controller
        tuned = tuned_spec(g.kp, g.ki, g.kd)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise HostError(f"output folder {out} exists and is not a directory")
    laws = baselines_path(args.network)
    pdff = load_baselines(laws)[1].coef if laws.exists() else None
    doc = cal.calibrate(plan, table1_spec(), ControllerSpec("NN (float64)", "nn", (("artifact", args.network),)), tuned,
                        progress=not args.no_progress, network_pdff=pdff)
    doc["network"] = {"file": str(args.network), "payload_sha256": a.sha256}
    cal.write(doc, out)
    print("\n".join(cal.summary_lines(doc)))
    print(f"wrote {out}/calibration.json, calibration.txt, fig_ratio_vs_noise.png and scenario.toml")
    return 0
