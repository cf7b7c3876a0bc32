"""The discrete-point C's loop bounds (`wcet: loop bound N`, read by tools/m4/wcet.py): every loop
carries one, the data-dependent candidate-scan bound the emitter derives holds for hostile inputs
(and is nearly reached), and the static bound of the step exists and covers what the profiler sees."""
from __future__ import annotations

import re

import numpy as np
import pytest

from codegen.units.dp import tables as T
from codegen.units.dp.emit import BLOCK, dp_sources, loop_bounds, window_counts
from codegen.units.dp.params import N_IN, DpParams
from codegen.units.dp.unit import DpUnit
from codegen.units.dp.vectors import gate_inputs

MARK = re.compile(r"/\* wcet: loop bound (\d+) \*/")
F32 = np.float32

pytestmark = pytest.mark.usefixtures("private_cache")  # conftest: a build cache of its own


def _clustered(n: int = 400, seed: int = 5) -> T.DpTables:
    """Two far clusters on every input and boxes that never reach across: the scan bound < N."""
    rng = np.random.default_rng(seed)
    side = rng.random((n, N_IN)) < 0.5
    X = np.where(side, 0.9, 0.0) + 0.1 * rng.random((n, N_IN))
    Y = 0.01 * rng.standard_normal((n, 3))
    return T.from_arrays(X, Y, DpParams(r=0.05, widen=4.0, s_limit=32, n_min=20))


TABLES = {"example": lambda: T.random_tables(),
          "clustered": _clustered,
          "few samples": lambda: T.random_tables(40, DpParams(s_limit=64, n_min=20, iterations=3), seed=1)}


@pytest.fixture(scope="module", params=sorted(TABLES))
def tables(request):
    return TABLES[request.param]()


# ----------------------------------------------------------------------------- (1) every loop

def test_every_for_carries_its_bound(tables):
    text = dp_sources(tables)["dp.c"]
    b = loop_bounds(tables)
    fors = [line for line in text.splitlines() if re.search(r"\bfor \(", line)]
    assert len(fors) >= 30
    for line in fors:
        assert MARK.search(line), f"a loop without `wcet: loop bound N`: {line.strip()}"
    marks = [line for line in text.splitlines() if re.search(r"wcet: loop bound \d", line)]
    assert len(marks) == len(fors), "an annotation away from a `for` line"
    by_loop = {line.split("{")[0].strip(): int(MARK.search(line).group(1)) for line in fors}
    assert by_loop["for (j = first[kb]; j < end; ++j)"] == b["scan_bound"]
    assert by_loop[f"for (p0 = 0u; p0 < m; p0 += {BLOCK}u)"] == b["block_bound"]
    assert by_loop["for (l = 0u; l < DP_N_SAMPLES; ++l)"] == tables.n
    assert by_loop["for (step = 0u; step < DP_BISECT_STEPS; ++step)"] == int(np.ceil(np.log2(tables.n + 1)))
    assert by_loop["for (it = 0u; it < DP_ITERATIONS; ++it)"] == tables.params.iterations
    assert b["m_bound"] == min(tables.params.s_limit, tables.n)


# ----------------------------------------------------------------------------- (2) the scan bound

def _queries(t: T.DpTables, n: int, seed: int) -> np.ndarray:
    """Hostile float32 rows: uniform over and beyond the sample range, on and beside samples,
    box edges landing exactly on samples (the unit's gate classes), huge, tiny, and rows holding
    NaN / Inf (the step refuses those before any scan)."""
    rng = np.random.default_rng(seed)
    lo, hi = t.X.min(axis=0).astype(np.float64), t.X.max(axis=0).astype(np.float64)
    span = hi - lo
    rows = [lo + span * rng.uniform(-0.5, 1.5, (n, N_IN)),
            t.X[rng.integers(0, t.n, n)].astype(np.float64) + span * rng.normal(0, 1e-3, (n, N_IN)),
            np.where(rng.random((n // 4, N_IN)) < 0.5, lo, hi)]
    rows += list(gate_inputs(t, n, seed).values())
    q = np.concatenate(rows).astype(F32)
    wild = np.array([np.nan, np.inf, -np.inf, 3e38, -3e38, 1e-40, 0.0, -0.0], dtype=F32)
    picks = rng.random(q.shape) < 0.05
    q[picks] = rng.choice(wild, int(picks.sum()))
    return q


def _densest(t: T.DpTables) -> np.ndarray:
    """Per level, the row whose every input sits mid-way in its densest box-wide window."""
    out = []
    for lv in range(t.n_levels):
        row = []
        for k in range(N_IN):
            v = np.sort(t.X[:, k].astype(np.float64))
            w = 2.0 * float(t.half_widths[lv, k])
            i = int(np.argmax(np.searchsorted(v, v + w, side="right") - np.arange(t.n)))
            row.append(v[i] + 0.5 * w)
        out.append(row)
    return np.array(out).astype(F32)


def _candidates(t: T.DpTables, Q: np.ndarray):
    """(rows, levels) min_k cnt[k]: the candidates the C's scan would visit at each level (its
    float32 box edges and closed-interval counts), and (rows,) those the step really scans: at
    every level it tries until one holds N_MIN points, none for a row with a non-finite input."""
    cols = [t.X[t.order[k].astype(np.int64), k] for k in range(N_IN)]
    X, n_min = t.X, t.params.n_min
    per_level = np.zeros((Q.shape[0], t.n_levels), dtype=np.int64)
    scanned = np.zeros(Q.shape[0], dtype=np.int64)
    pending = np.all(np.isfinite(Q), axis=1)
    with np.errstate(over="ignore", invalid="ignore"):
        for lv in range(t.n_levels):
            lo, hi = Q - t.half_widths[lv], Q + t.half_widths[lv]        # float32, as the C
            cnt = np.stack([np.searchsorted(cols[k], hi[:, k], side="right")
                            - np.searchsorted(cols[k], lo[:, k], side="left") for k in range(N_IN)], axis=1)
            per_level[:, lv] = cnt.min(axis=1)
            for r in np.flatnonzero(pending & (per_level[:, lv] >= n_min)):
                scanned[r] = max(scanned[r], per_level[r, lv])
                if np.all((X >= lo[r]) & (X <= hi[r]), axis=1).sum() >= n_min:
                    pending[r] = False
    per_level[~np.all(np.isfinite(Q), axis=1)] = 0
    return per_level, scanned


def test_the_scan_bound_holds_for_hostile_inputs(tables):
    bound = loop_bounds(tables)["scan_bound"]
    Q = np.concatenate([_queries(tables, 150, seed=11), _densest(tables)])
    per_level, scanned = _candidates(tables, Q)
    assert 0 < scanned.max() <= per_level.max() <= bound <= tables.n
    # nearly reached: the densest windows' rows come within the float32 margin of W at every level
    W = window_counts(tables).min(axis=1)
    reached = per_level[-tables.n_levels:].diagonal()
    assert np.all(reached <= W) and np.all(reached >= W - 2), (reached, W)


def test_the_clustered_tables_bound_the_scan_below_n():
    t = _clustered()
    assert loop_bounds(t)["scan_bound"] < 0.7 * t.n


# ----------------------------------------------------------------------------- (3) the static bound

def _analysis(unit):
    from tools.m4.elf import Image
    from tools.m4.wcet import Analysis
    from tools.runners import arm_build
    build = arm_build(unit)
    return build, Analysis(Image(build.elf), build.elf.parent / "src")


def test_every_machine_loop_finds_its_bound(tables):
    build, an = _analysis(DpUnit(tables))
    an.bound("dp_step")                         # raises on a loop without a bound
    text = (build.elf.parent / "src" / "dp.c").read_text().splitlines()
    loops = [(w, k) for f in an.analysed() for _h, w, k in f.loops]
    assert len(loops) >= 25
    for where, k in loops:                      # each on an annotated `for`, at most one run more
        n = int(MARK.search(text[int(where.split(":")[1]) - 1]).group(1))
        assert k in (n, n + 1), (where, k, n)
    # the level loop exits at its end only: N_LEVELS runs of the body, no more
    assert [k for w, k in loops if "l < DP_N_LEVELS" in text[int(w.split(":")[1]) - 1]] == [tables.n_levels]


def test_static_bound_covers_the_profiled_steps():
    from tools.report import cycle_report
    unit = DpUnit(T.random_tables())
    _build, an = _analysis(unit)
    fb = an.bound(unit.step_symbol)
    rep = cycle_report(unit, ("ideal", "art"), per_class=3, seed=0)   # raises if a count exceeds the bound
    for mode in ("ideal", "art"):
        sampled, bound = rep["cycles"][mode]["max"], rep["bound"]["strict"][mode]
        assert sampled <= bound == fb.cycles[("strict", mode)]
    assert rep["bound"]["strict"]["ideal"] < 6 * rep["cycles"]["ideal"]["max"]
