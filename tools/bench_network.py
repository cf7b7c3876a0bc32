"""Side-by-side benchmark of the network path on the Cortex-M4 cycle model (issue 4; not a test).

The same 12-40-3 network (an artifact file, e.g. a trained one, or a seeded random one) as
  * our generated C (the network unit, codegen/units/network) at -O2 (the flight level), -Os and -O0 (firmware.flags.with_opt),
  * emlearn's C (pip package `emlearn`, optional extra `bench`: its "loadable" MLP, eml_net.h,
    tanhf from newlib's libm), built by firmware/arm.py with peer=True: the same flags minus
    -Werror (its headers are not -Wextra -pedantic clean), libm and newlib-nano linked,
  * the same emlearn C with our tanh (sg_tanhf, the network path's own function) in place of
    newlib's tanhf: the fair comparison of the two MLP codes, since newlib's tanhf is about half
    of emlearn's cycles,
each run over the input classes of `staregen cycles` (inside the envelope, edges, outside,
special values) under the cycle model in the three memory modes, plus the paper's 3.1 ms.

emlearn's C has no mapminmax: it gets the normalised inputs (MATLAB's mapminmax in float32 on the host,
mapminmax_f32 below; our C has the map folded into its first layer instead) and its normalised outputs
are mapped back on the host in float64, so its cycles are those of the MLP alone and its error that of
its MLP and libm tanhf.

Usage:  python tools/bench_network.py [--artifact A.json] [--per-class 250] [--md out.md]
"""
from __future__ import annotations

import argparse
import datetime
import platform
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from codegen import artifact as art  # noqa: E402
from codegen.cgen import math_sources  # noqa: E402
from codegen.units.network import golden, reference  # noqa: E402
from codegen.units.network.unit import NetworkUnit  # noqa: E402
from codegen.units.network.vectors import class_vectors  # noqa: E402
from firmware import arm  # noqa: E402
from tools import size  # noqa: E402
from tools.cycles import CLOCK_HZ, profile_entry  # noqa: E402
from tools.m4.harness import Harness  # noqa: E402
from tools.m4.profile import MODES  # noqa: E402
from tools.runners import arm_build  # noqa: E402

PAPER_MS = 3.1                                   # the paper's network path on its M4F
PAPER_CYCLES = round(PAPER_MS * 1e-3 * CLOCK_HZ)  # 520,800 at 168 MHz
HARNESS_OBJECTS = {"startup.o", "harness.o", "adapter.o"}
EML_NAME = "emlnet"


@dataclass
class Row:
    name: str
    cycles: dict          # mode -> worst case over all vectors
    inside: int           # worst case, ideal, inside the envelope
    flash: int | None     # bytes of the network code and data (libraries included for emlearn)
    stack: int | None     # painted stack depth of the entry call, bytes
    max_error: float | None       # max |y - y_float64| inside the envelope, output units
    rel_error: float | None       # the same over the output range (xmax - xmin)
    note: str = ""


def _records(classes: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    return {c: x.view(np.uint8).reshape(x.shape[0], -1) for c, x in classes.items()}


def _profile(elf: Path, entry: str, classes: dict[str, np.ndarray]):
    return profile_entry(elf, entry, _records(classes), MODES)


def _eval(elf: Path, x: np.ndarray, n_out: int) -> np.ndarray:
    """float32 rows through a stateless build's records harness in the emulator."""
    out = Harness(elf).run(np.ascontiguousarray(x).view(np.uint8).reshape(x.shape[0], -1))
    return out.view(np.float32).reshape(x.shape[0], n_out)


def _errors(a: art.Artifact, y: np.ndarray, x_inside: np.ndarray) -> tuple[float, float]:
    err = np.abs(y.astype(np.float64) - reference.reference_eval64(a, x_inside))
    span = (a.output_map.xmax - a.output_map.xmin).astype(np.float64)
    return float(err.max()), float((err / span).max())


def ours(a: art.Artifact, opt: str, classes: dict[str, np.ndarray]) -> Row:
    """Our generated network path at one optimisation level (bit-exactness checked on the way)."""
    build = arm_build(NetworkUnit(a), opt=opt)
    prof = _profile(build.elf, "network_eval", classes)
    x_in = classes["inside"]
    y = _eval(build.elf, x_in, a.n_out)
    g = golden.network_eval(a, x_in)
    exact = bool(np.array_equal(y.view(np.uint32), g.view(np.uint32)))
    flash = size.sizes(build.elf, build.map).of_objects(["network.o", "sg_math.o"])["flash"]
    err, rel = _errors(a, y, x_in)
    return Row(f"staregen C {opt}", {m: prof.cycles[m]["max"] for m in prof.modes},
               prof.by_class["inside"]["ideal"]["max"], flash, prof.stack_painted, err, rel,
               "bit-exact with the golden model" if exact else "NOT bit-exact with the golden model")


def emlearn_sources(a: art.Artifact, fast_tanh: bool = False) -> dict[str, str]:
    """emlearn's loadable MLP of the artifact's weights + a `<name>_eval(x, y)` entry for the
    harness adapter, and emlearn's headers (copied from the installed package). fast_tanh: its
    activation's tanhf call goes to our sg_tanhf (a macro before its headers), sg_math added."""
    import emlearn
    from emlearn import net

    code = net.c_generate_net_loadable(["tanh", "identity"], [a.W1.T.astype(np.float32), a.W2.T.astype(np.float32)],
                                       [a.b1, a.b2], prefix=EML_NAME)
    P = EML_NAME.upper()
    header = (f"#define {P}_N_IN {a.n_in}\n#define {P}_N_OUT {a.n_out}\n"
              f"void {EML_NAME}_eval(const float *xn, float *yn);\n")
    entry = (f'\n#include "{EML_NAME}.h"\n'
             f"/* normalised inputs in, normalised outputs out (emlearn has no mapminmax) */\n"
             f"void {EML_NAME}_eval(const float *xn, float *yn)\n{{\n"
             f"    eml_net_regress(&{EML_NAME}, xn, {a.n_in}, yn, {a.n_out});\n}}\n")
    if fast_tanh:
        code = '#include <math.h>\n#include "sg_math.h"\n#define tanhf(x) sg_tanhf(x)\n' + code
    sources = {f"{EML_NAME}.c": code + entry, f"{EML_NAME}.h": header}
    if fast_tanh:
        sources.update(math_sources())
    pkg = Path(emlearn.__file__).parent
    for h in sorted(pkg.glob("eml_*.h")):
        sources[h.name] = h.read_text()
    return sources


def mapminmax_f32(a: art.Artifact, x: np.ndarray) -> np.ndarray:
    """MATLAB's mapminmax of the inputs in float32, (x - xoffset) * gain + ymin: emlearn's inputs."""
    m = a.input_map
    with np.errstate(all="ignore"):
        return ((x - m.xoffset) * m.gain + np.float32(m.ymin)).astype(np.float32)


def emlearn_row(a: art.Artifact, classes: dict[str, np.ndarray], fast_tanh: bool = False) -> Row:
    import emlearn

    P = EML_NAME.upper()
    adapter = arm.render_adapter("records", entry=EML_NAME, header=f"{EML_NAME}.h", step=f"{EML_NAME}_eval", init="",
                                 layout_checks=[f"{P}_N_IN == {a.n_in}", f"{P}_N_OUT == {a.n_out}"],
                                 input_words=a.n_in, output_words=a.n_out, state_words=0)
    build = arm.build(emlearn_sources(a, fast_tanh), adapter, opt="-O2", peer=True)
    xn_classes = {c: mapminmax_f32(a, x) for c, x in classes.items()}
    prof = _profile(build.elf, f"{EML_NAME}_eval", xn_classes)
    yn = _eval(build.elf, xn_classes["inside"], a.n_out)
    om = a.output_map
    y = (yn.astype(np.float64) - float(om.ymin)) / om.gain.astype(np.float64) + om.xoffset.astype(np.float64)
    err, rel = _errors(a, y, classes["inside"])
    per_object = size.sizes(build.elf, build.map).per_object
    flash = sum(r["flash"] for o, r in per_object.items() if o not in HARNESS_OBJECTS)
    tanh = "our sg_tanhf" if fast_tanh else "libm tanhf, newlib-nano"
    return Row(f"emlearn {emlearn.__version__} -O2" + (" + our tanh" if fast_tanh else ""),
               {m: prof.cycles[m]["max"] for m in prof.modes},
               prof.by_class["inside"]["ideal"]["max"], flash, prof.stack_painted, err, rel,
               f"MLP only (normalised in/out); {tanh}; -Werror dropped")


def _fmt(v, spec: str = ",") -> str:
    return "–" if v is None else format(v, spec)


def markdown(rows: list[Row], base: Row) -> list[str]:
    lines = ["| build | ideal | art | pessimistic | inside, ideal | µs @168 MHz (ideal) | vs ours -O2 (ideal) "
             "| flash B | stack B | max \\|error\\| vs float64 | / output range | note |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        ideal = r.cycles.get("ideal")
        lines.append(
            f"| {r.name} | {_fmt(ideal)} | {_fmt(r.cycles.get('art'))} | {_fmt(r.cycles.get('pessimistic'))} "
            f"| {_fmt(r.inside)} | {ideal / CLOCK_HZ * 1e6:.2f} | {ideal / base.cycles['ideal']:.2f}× "
            f"| {_fmt(r.flash)} | {_fmt(r.stack)} | {_fmt(r.max_error, '.3g')} | {_fmt(r.rel_error, '.2g')} "
            f"| {r.note} |")
    return lines


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--artifact", help="artifact JSON (default: random 12-40-3, seed 1)")
    p.add_argument("--per-class", type=int, default=250, help="vectors per input class (default 250)")
    p.add_argument("--seed", type=int, default=0, help="vector seed (default 0)")
    p.add_argument("--md", help="also write the Markdown table to this file")
    args = p.parse_args(argv)
    a = art.load(args.artifact) if args.artifact else art.random_artifact((12, 40, 3), seed=1)
    classes = class_vectors(a.envelope, args.per_class, args.seed)
    rows = [ours(a, opt, classes) for opt in ("-O2", "-Os", "-O0")]
    rows.append(emlearn_row(a, classes))
    rows.append(emlearn_row(a, classes, fast_tanh=True))
    paper = Row(f"paper ({PAPER_MS} ms on its M4F)", {"ideal": PAPER_CYCLES}, None, None, None, None, None,
                "as published (MATLAB-generated code); 168 MHz")
    rows.append(paper)
    base, eml, eml_fast = rows[0], rows[3], rows[4]
    n = sum(x.shape[0] for x in classes.values())
    out = [f"Artifact {a.sha256[:16]}… ({a.shape_text}, {a.metadata.get('creator', '')}); "
           f"{n} vectors ({args.per_class} per class: {', '.join(classes)}), seed {args.seed}; "
           f"worst case per call over all of them unless stated; {platform.machine()}, "
           f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, {arm.compiler_version()}.",
           "", *markdown(rows, base), "",
           "Strict timing table (every TRM stall rule); sampled worst case.",
           f"emlearn / ours (-O2), ideal, worst case: as shipped {eml.cycles['ideal'] / base.cycles['ideal']:.2f}×, "
           f"with our tanh (the fair ratio: the same tanh on both sides) "
           f"{eml_fast.cycles['ideal'] / base.cycles['ideal']:.2f}×; "
           f"paper / ours: {PAPER_CYCLES / base.cycles['ideal']:.0f}×."]
    text = "\n".join(out)
    print(text)
    if args.md:
        Path(args.md).write_text(text + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
