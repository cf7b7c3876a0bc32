"""`staregen impulse [--controller nn|nn-c|nn-arm|pid|pid-c] [--artifact FILE] [--duration S] [--out DIR]`.

Paper 001 Sec. 7.8 / Fig. 15: 1 N·m on each axis from 30 s for 0.5 s while staring at the
central target; prints when the PID took over and when the network was back, writes
impulse.json and impulse.png (Euler angle and rate errors, mode) into --out.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from host.cli.args import add_scenario_argument, load_scenario, parse_int, parse_number
from host.cli.simulate import controller_options
from host.control.controllers import CONTROLLERS
from host.errors import HostError
from host.outputs import check_output_folder, json_marker_owner
from codegen import atomic


def register(subparsers) -> None:
    p = subparsers.add_parser("impulse", help="impulse response (paper 001 Fig. 15): PID takeover and hand-back",
                              description=__doc__.splitlines()[0])
    p.add_argument("--controller", default="nn", help=f"controller ({', '.join(sorted(CONTROLLERS))}; default nn)")
    p.add_argument("--artifact", default=None, metavar="FILE",
                   help="model artifact (network controllers); default: the stand-in network")
    p.add_argument("--duration", default="60", help="simulated seconds (default 60, at least 31)")
    p.add_argument("--seed", default="0", help="noise seed (default 0)")
    add_scenario_argument(p)
    p.add_argument("--out", default="out/impulse", help="output folder (default out/impulse)")
    p.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    from host.sim import impulse

    if args.controller not in CONTROLLERS:
        raise HostError(f"unknown controller {args.controller!r} (known: {', '.join(sorted(CONTROLLERS))})")
    duration = parse_number(args.duration, "--duration", positive=True)
    if duration <= impulse.IMPULSE_START + impulse.IMPULSE_LENGTH:
        raise HostError(f"--duration must exceed {impulse.IMPULSE_START + impulse.IMPULSE_LENGTH:g} s "
                        f"(the impulse ends then), got {duration:g}")
    options = controller_options(args)
    out = Path(args.out)
    check_output_folder(out, json_marker_owner("impulse.json"), [args.artifact, args.scenario])
    scenario = load_scenario(args.scenario)
    r = impulse.run(args.controller, options.get("artifact"), duration, parse_int(args.seed, "--seed"), scenario.errors)
    try:
        with atomic.directory(out) as tmp:
            impulse.write(r, tmp, args.controller, scenario.describe())
    except OSError as exc:
        raise HostError(f"cannot write output folder {out}: {exc.strerror or exc}") from None
    d = r.as_dict()
    print(f"impulse response, {args.controller}: PID from {d['t_pid_first_s']} s, network back at "
          f"{d['t_nn_back_s']} s ({d['nn_back_after_impulse_end_s']:.1f} s after the impulse ended)"
          if d["t_nn_back_s"] is not None else f"impulse response, {args.controller}: network NOT back by the end")
    print(f"  peak |A_bd| {d['peak_A_bd_deg']:.4f} deg, peak |omega_e| {d['peak_omega_e_deg_s']:.4f} deg/s, "
          f"last 5 s max |A_bd| {d['final_max_A_bd_deg']:.2e} deg")
    print(f"wrote {out}/impulse.json, {out}/impulse.png")
    return 0
