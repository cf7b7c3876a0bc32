"""Exhaustive ulp measurement of codegen/csrc/sg_math.c (all 2^32 float32 inputs per function).

    python tools/ulp_sweep.py [--func NAME|all] [--jobs 2] [--chunks 64] [--out DIR]

Compiles tools/ulp_sweep.c with the flight flags (firmware/flags.py COMMON; -lm only for the
float64 reference), splits the 2^32 bit patterns into chunks run by --jobs processes, merges
the per-chunk statistics and prints/writes a table: max ulp, the argument where it occurs,
the number of results above 0.5 and 1 ulp, and class mismatches (Inf/NaN/0 expected but not
produced). atan2f and powf_pos are sampled (--samples; powf_pos:L draws y so that |y ln x| <= L).
Results go to DIR/ulp_<func>.json; DIR/ulp_table.md tabulates every function measured into DIR
(default out/ulp_sweep).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import platform
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from firmware.flags import COMMON  # noqa: E402

CSRC = ROOT / "codegen" / "csrc"
SWEEP_C = ROOT / "tools" / "ulp_sweep.c"
EXHAUSTIVE = ["tanhf", "expf", "logf", "sinf", "cosf", "asinf", "sqrtf"]
SAMPLED = ["atan2f", "powf_pos:1", "powf_pos:10", "powf_pos:88"]


def build(cache: Path) -> Path:
    """Compile the sweep binary into cache/, keyed by the sources' hash."""
    sources = [SWEEP_C, CSRC / "sg_math.c", CSRC / "sg_math.h"]
    key = hashlib.sha256(b"".join(p.read_bytes() for p in sources) + " ".join(COMMON).encode())
    exe = cache / f"ulp_sweep_{key.hexdigest()[:16]}"
    if not exe.exists():
        cache.mkdir(parents=True, exist_ok=True)
        cmd = ["gcc", *COMMON, "-I", str(CSRC), str(SWEEP_C), str(CSRC / "sg_math.c"),
               "-o", str(exe), "-lm"]
        subprocess.run(cmd, check=True)
    return exe


def parse(line: str) -> dict:
    fields = dict(kv.split("=", 1) for kv in line.split())
    out: dict = {"func": fields.pop("func")}
    for k, v in fields.items():
        out[k] = float(v) if k == "max_ulp" else (v if k.startswith("arg_") else int(v))
    return out


def merge(parts: list[dict]) -> dict:
    best = max(parts, key=lambda p: p["max_ulp"])
    total = {"func": parts[0]["func"], "max_ulp": best["max_ulp"],
             "arg_x": best["arg_x"], "arg_y": best["arg_y"]}
    for k in ("n", "gt_half", "gt_one", "special_bad", "outside_n", "outside_bad"):
        total[k] = sum(p[k] for p in parts)
    return total


def run_chunks(exe: Path, argvs: list[list[str]], jobs: int) -> list[dict]:
    def one(argv: list[str]) -> dict:
        res = subprocess.run([str(exe), *argv], check=True, capture_output=True, text=True)
        if res.stderr:
            print(res.stderr.strip(), file=sys.stderr)
        return parse(res.stdout.strip())

    with ThreadPoolExecutor(max_workers=jobs) as pool:
        return list(pool.map(one, argvs))


def sweep(exe: Path, func: str, jobs: int, chunks: int, samples: int) -> dict:
    t0 = time.time()
    if func in EXHAUSTIVE:
        edges = np.linspace(0, 2**32, chunks + 1, dtype=np.uint64)
        argvs = [["range", func, str(lo), str(hi)] for lo, hi in zip(edges[:-1], edges[1:])]
        mode = "exhaustive"
    else:
        per = samples // chunks
        argvs = [["sample", func, str(seed + 1), str(per)] for seed in range(chunks)]
        mode = "sampled"
    result = merge(run_chunks(exe, argvs, jobs))
    result.update(mode=mode, seconds=round(time.time() - t0, 1))
    x = np.array([int(result["arg_x"], 16)], np.uint32).view(np.float32)[0]
    y = np.array([int(result["arg_y"], 16)], np.uint32).view(np.float32)[0]
    result["arg"] = f"{x!r}" if mode == "exhaustive" else f"({x!r}, {y!r})"
    return result


def table(results: list[dict]) -> str:
    head = ("| function | mode | inputs | max ulp | at | > 0.5 ulp | > 1 ulp | class mismatches |"
            " outside domain (bad/n) |\n|---|---|---|---|---|---|---|---|---|\n")
    rows = [f"| {r['func']} | {r['mode']} | {r['n']} | {r['max_ulp']:.3f} | {r['arg']} | "
            f"{r['gt_half']} | {r['gt_one']} | {r['special_bad']} | "
            f"{r['outside_bad']}/{r['outside_n']} |" for r in results]
    return head + "\n".join(rows) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--func", default="all", help="one of %s, or all" % (EXHAUSTIVE + SAMPLED))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--chunks", type=int, default=64)
    ap.add_argument("--samples", type=int, default=64_000_000)
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "ulp_sweep")
    args = ap.parse_args(argv)
    funcs = EXHAUSTIVE + SAMPLED if args.func == "all" else [args.func]
    exe = build(args.out / "build")
    results = []
    for func in funcs:
        r = sweep(exe, func, args.jobs, args.chunks, args.samples)
        r["machine"] = f"{platform.node()} {platform.machine()} {platform.processor()}".strip()
        r["date"] = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        print(json.dumps(r), flush=True)
        (args.out / f"ulp_{func.replace(':', '_')}.json").write_text(json.dumps(r, indent=1))
        results.append(r)
    # The table covers every function measured into this folder so far (one run per function).
    merged = {r["func"]: r for r in map(json.loads, map(Path.read_text,
                                                           sorted(args.out.glob("ulp_*.json"))))}
    order = EXHAUSTIVE + SAMPLED
    text = table(sorted(merged.values(), key=lambda r: order.index(r["func"])
                        if r["func"] in order else len(order)))
    print(text)
    (args.out / "ulp_table.md").write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
