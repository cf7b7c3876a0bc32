"""Static worst-case cycle bound of a function of the ARM ELF (SPEC section 7, docs/cycle-model.md).

The bound is the longest path through the control-flow graph recovered from the code, costed with
the same timing table as the profiler (tools/m4/timing.py), taking the conservative choice where
the profiler resolves timing at run time:

- blocks are summed with the profiler's own block summary (in-block pipelining and strict pair
  rules); an IT-conditional instruction is charged as executed;
- an edge carries what depends on the path: the pair rules across a fall-through, P on a taken
  conditional branch, the strict target-alignment cycle after every taken transfer, the callee's
  bound on a call;
- loops are the natural loops of the graph (an irreducible one is an error); each must carry a
  bound in the generated C, a comment `wcet: loop bound N` on a line of its controlling branch
  (N: most iterations of the body per entry), found through the DWARF line table (the ARM build
  compiles with -g, which leaves the code unchanged);
- the longest path is an integer linear programme over edge counts (IPET: flow conservation, one
  entry, loop bounds), solved with HiGHS (scipy.optimize.milp), one function at a time, callees
  first (context-insensitive: each call costs the callee's bound).

Memory modes: `ideal` (0 wait states) and `art` (5 wait states, ART caches cold at the call). For
`art`, every flash line of code a scope can fetch misses at most once per entry of a scope whose
code fits the 64-line instruction cache (the scopes: the function with its callees, else each
loop nest that fits, else every block execution misses on each of its lines but a first line
that the block it follows, not through a call, ends in: the ART's current line); data reads from
flash are literal-pool loads (their lines known, the same rule with the 8-line data cache) and,
unless the image keeps no read-only data in flash, every other load, charged a miss each time.
"""
from __future__ import annotations

import bisect
import re
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from elftools.elf.elffile import ELFFile
from scipy.optimize import Bounds, LinearConstraint, milp

from tools.errors import ToolError
from tools.m4.decode import LINE_SHIFT, Decoder, Insn, literal_address, words_read
from tools.m4.elf import Image
from tools.m4.machine import FLASH
from tools.m4.memory import ART_D_LINES, ART_I_LINES, WAIT_STATES
from tools.m4.timing import FLOW_CALL, FLOW_COND, FLOW_NONE, TABLES, entry_extra, pair

BOUND_MARK = re.compile(r"wcet: loop bound (\d+)(?: lines (\d+))?\b")


def _is_return(ins: Insn) -> bool:
    """BX LR, POP {.., pc}, LDR pc, [sp], #4 (any condition)."""
    mnem, _, ops = ins.text.partition(" ")
    return (mnem.startswith("bx") and ops == "lr" or mnem.startswith("pop") and "pc" in ops
            or mnem.startswith("ldr") and ops.startswith("pc, [sp"))


@dataclass
class _Block:
    addr: int
    insns: list[Insn]
    cost: dict                       # table -> cycles (conservative: IT-conditional instructions executed)
    succ: list = field(default_factory=list)   # (dest addr | None for exit, {table: cycles}, kind)
    call: str | None = None          # callee name when the block ends in a call (edge to the fall-through)
    summary: object = None           # the decoder's block summary (head and tail for the pair rules)

    @property
    def end(self) -> int:
        last = self.insns[-1]
        return last.addr + last.size


@dataclass
class FunctionBound:
    name: str
    cycles: dict                     # (table, mode) -> bound
    loops: list                      # (header addr, source "file:line", K header executions per entry)
    callees: list
    art_parts: dict                  # flash stalls bound by source: code, literal, data


class LineTable:
    """Address -> (source file name, line) from the DWARF line programme."""

    def __init__(self, elf: Path):
        rows = []
        with open(elf, "rb") as fh:
            dwarf = ELFFile(fh).get_dwarf_info() if ELFFile(fh).has_dwarf_info() else None
            if dwarf is None:
                raise ToolError(f"{elf}: no DWARF line table (the ARM build compiles with -g)")
            for cu in dwarf.iter_CUs():
                prog = dwarf.line_program_for_CU(cu)
                if prog is None:
                    continue
                names = _file_names(prog)
                for entry in prog.get_entries():
                    st = entry.state
                    if st is not None and not st.end_sequence:
                        rows.append((st.address, names.get(st.file, "?"), st.line))
        # By address only, stably: where one address has several rows, the programme's last one
        # (the instruction's own line) is the one bisect finds.
        self.rows = sorted(rows, key=lambda r: r[0])
        self._addrs = [r[0] for r in self.rows]

    def line_of(self, addr: int) -> tuple[str, int] | None:
        i = bisect.bisect_right(self._addrs, addr) - 1
        return (self.rows[i][1], self.rows[i][2]) if i >= 0 else None


def _file_names(prog) -> dict[int, str]:
    entries = prog.header["file_entry"]
    base = 0 if prog.header["version"] >= 5 else 1
    return {i + base: Path(e.name.decode()).name for i, e in enumerate(entries)}


def loop_annotations(sources: Path) -> dict[str, list[tuple[int, int, int]]]:
    """{file name: [(first line, last line, bound)]}: the source extent of every loop annotated
    `wcet: loop bound N` in the build's sources. In C the extent runs from the annotated line to
    the brace closing the block it opens; in assembly the annotation says how many lines it
    covers (`wcet: loop bound N lines K`)."""
    out: dict[str, list[tuple[int, int, int]]] = {}
    for path in sorted([*sources.glob("*.c"), *sources.glob("*.h"), *sources.glob("*.S")]):
        lines = path.read_text().splitlines()
        for no, text in enumerate(lines, start=1):
            m = BOUND_MARK.search(text)
            if m:
                span = int(m.group(2)) if m.group(2) else None
                last = no + span - 1 if span else _closing_line(lines, no, path.name)
                out.setdefault(path.name, []).append((no, last, int(m.group(1))))
    return out


def _closing_line(lines: list[str], first: int, fname: str) -> int:
    """Line of the brace closing the block opened on line `first` (comments ignored)."""
    depth, opened = 0, False
    for no in range(first, len(lines) + 1):
        code = re.sub(r"/\*.*?\*/|//.*$", "", lines[no - 1])
        for ch in code:
            if ch == "{":
                depth, opened = depth + 1, True
            elif ch == "}":
                depth -= 1
                if opened and depth == 0:
                    return no
    raise ToolError(f"{fname}:{first}: `wcet: loop bound` on a line that opens no block")


class Analysis:
    """Static bounds of the functions of one image (memoised per function)."""

    def __init__(self, image: Image, sources: Path, flash_data_is_literals_only: bool | None = None):
        self.image = image
        self.dec = Decoder(image, (FLASH[0], FLASH[0] + FLASH[1]))
        self.lines = LineTable(image.path)
        self.sources = Path(sources)
        self.marks = loop_annotations(self.sources)
        self._extents: dict[tuple[str, str], set[int] | None] = {}
        self.flash_tables = sorted(o.name for o in image.flash_objects(FLASH))
        self.literals_only = (not self.flash_tables if flash_data_is_literals_only is None
                              else flash_data_is_literals_only)
        self.starts = {f.start: f.name for f in image.functions}
        self._done: dict[str, FunctionBound] = {}
        self._active: list[str] = []
        self._graphs: dict[str, dict[int, _Block]] = {}
        self._local: dict[str, tuple[int, int, int]] = {}
        for f in image.functions:
            if FLASH[0] <= f.start < FLASH[0] + FLASH[1] and f.size:
                self.dec.scan_it(f.start, f.size)

    # --- public ----------------------------------------------------------------------------
    def bound(self, name: str) -> FunctionBound:
        if name in self._done:
            return self._done[name]
        if name in self._active:
            raise ToolError(f"recursion through {' -> '.join(self._active + [name])}: no static bound")
        self._active.append(name)
        try:
            fb = self._bound(name)
        finally:
            self._active.pop()
        self._done[name] = fb
        return fb

    def analysed(self) -> list[FunctionBound]:
        """Every function bounded so far (the entry and what it calls)."""
        return list(self._done.values())

    # --- control-flow graph ----------------------------------------------------------------
    def graph(self, name: str) -> dict[int, _Block]:
        if name not in self._graphs:
            self._graphs[name] = self._build_graph(name)
        return self._graphs[name]

    def _range(self, name: str) -> tuple[int, int, int]:
        """(start, lo, hi) of a function, or of a local subroutine (a BL target inside one)."""
        if name in self._local:
            return self._local[name]
        fn = self.image.function(name)
        return fn.start, fn.start, fn.start + fn.size

    def _build_graph(self, name: str) -> dict[int, _Block]:
        start, lo, hi = self._range(name)
        insns: dict[int, Insn] = {}
        leaders, work = {start}, [start]
        while work:
            a = work.pop()
            while a not in insns:
                if not lo <= a < hi:
                    raise ToolError(f"{name}: control flow leaves the function at 0x{a:08x}")
                ins = self.dec.insn(a)
                insns[a] = ins
                nxt = a + ins.size
                kind = self._kind(name, ins)
                if kind in ("cond", "it-exit", "it-jump"):
                    tgt = ins.target
                    if kind != "it-exit":
                        self._check_target(name, ins, lo, hi)
                        leaders.add(tgt)
                        work.append(tgt)
                    leaders.add(nxt)
                    a = nxt
                elif kind == "jump":
                    self._check_target(name, ins, lo, hi)
                    leaders.add(ins.target)
                    work.append(ins.target)
                    break
                elif kind in ("return", "tail", "trap"):
                    break
                elif kind == "call":
                    leaders.add(nxt)
                    a = nxt
                else:
                    a = nxt
        return self._blocks(name, insns, leaders)

    def _kind(self, name: str, ins: Insn) -> str:
        c = ins.cost
        in_it = ins.addr in self.dec.it_scanned
        if ins.text.startswith(("bkpt", "udf")):
            return "trap"  # a fault stops the step: no path continues
        if c.flow == FLOW_NONE:
            return "plain"
        if c.flow == FLOW_CALL:
            if ins.target is None:
                raise ToolError(f"{name}: indirect call at 0x{ins.addr:08x} ({ins.text}): no static bound")
            return "call"
        if c.flow == FLOW_COND:
            return "cond"
        mnem = ins.text.split()[0]
        if _is_return(ins):
            return "it-exit" if in_it else "return"
        if mnem.startswith("b") and not mnem.startswith("bx") and not mnem.startswith("bl") and ins.target is not None:
            if ins.target in self.starts and self.starts[ins.target] != name:
                if in_it:
                    raise ToolError(f"{name}: conditional tail call at 0x{ins.addr:08x}: not supported")
                return "tail"
            return "it-jump" if in_it else "jump"
        raise ToolError(f"{name}: indirect jump at 0x{ins.addr:08x} ({ins.text}): no static bound")

    @staticmethod
    def _check_target(name: str, ins: Insn, lo: int, hi: int) -> None:
        if ins.target is None or not lo <= ins.target < hi:
            raise ToolError(f"{name}: branch at 0x{ins.addr:08x} ({ins.text}) leaves the function")

    def _blocks(self, name: str, insns: dict[int, Insn], leaders: set[int]) -> dict[int, _Block]:
        blocks: dict[int, _Block] = {}
        cur: list[Insn] = []
        for a in sorted(insns):
            if cur and (a in leaders or cur[-1].addr + cur[-1].size != a or self._ends_block(name, cur[-1])):
                blocks[cur[0].addr] = self._block(name, cur)
                cur = []
            cur.append(insns[a])
        if cur:
            blocks[cur[0].addr] = self._block(name, cur)
        for b in blocks.values():
            self._edges(name, b, blocks)
        return blocks

    def _ends_block(self, name: str, ins: Insn) -> bool:
        return self._kind(name, ins) != "plain"

    def _block(self, name: str, insns: list[Insn]) -> _Block:
        first = insns[0]
        summary = self.dec.summarise(first.addr, sum(i.size for i in insns), insns)
        it_s = it_l = 0
        for ins in insns[:-1]:
            if ins.addr in self.dec.it_scanned:  # charged as executed: the conservative choice
                es, el = self.dec.it_scanned[ins.addr]
                it_s, it_l = it_s + max(es, 0), it_l + max(el, 0)
        last = insns[-1]
        if last.addr in self.dec.it_scanned and self._kind(name, last) == "plain":
            es, el = self.dec.it_scanned[last.addr]
            it_s, it_l = it_s + max(es, 0), it_l + max(el, 0)
        return _Block(first.addr, insns, {"strict": summary.cost + it_s, "lenient": summary.cost_l + it_l},
                      summary=summary)

    def _edges(self, name: str, b: _Block, blocks: dict[int, _Block]) -> None:
        last = b.insns[-1]
        kind = self._kind(name, last)
        fall = b.end

        def taken(dest: int, extra: int) -> dict:
            return {"strict": extra + entry_extra(self.dec.insn(dest).cost, dest), "lenient": extra}

        def falls(dest: int) -> dict:
            nb = blocks[dest]
            s, n = pair(b.summary.tail[0], nb.summary.head[0], b.summary.tail[1], nb.summary.head[1])
            return {"strict": s, "lenient": n}

        if kind == "plain":
            b.succ.append((fall, falls(fall), "fall"))
        elif kind == "cond":
            b.succ.append((fall, falls(fall), "fall"))
            b.succ.append((last.target, taken(last.target, last.cost.taken_extra), "taken"))
        elif kind == "jump":
            b.succ.append((last.target, taken(last.target, 0), "taken"))
        elif kind == "it-jump":
            es, el = self.dec.it_scanned[last.addr]
            b.succ.append((fall, falls(fall), "fall"))
            t = taken(last.target, 0)
            b.succ.append((last.target, {"strict": t["strict"] + es, "lenient": el}, "taken"))
        elif kind == "it-exit":
            es, el = self.dec.it_scanned[last.addr]
            b.succ.append((fall, falls(fall), "fall"))
            b.succ.append((None, {"strict": es, "lenient": el}, "exit"))
        elif kind == "return":
            b.succ.append((None, {"strict": 0, "lenient": 0}, "exit"))
        elif kind == "tail":
            b.call = self.starts[last.target]
            b.succ.append((None, {"strict": 0, "lenient": 0}, "tail"))
        elif kind == "call":
            b.call = self.starts.get(last.target)
            if b.call is None:  # a subroutine inside this function (hand-written assembly)
                _s, lo, hi = self._range(name)
                if not lo <= last.target < hi:
                    raise ToolError(f"{name}: call at 0x{last.addr:08x} to 0x{last.target:08x}, not a function")
                b.call = f"{name}@0x{last.target:08x}"
                self._local[b.call] = (last.target, lo, hi)
            b.succ.append((fall, taken(fall, 0), "return"))

    # --- loops -----------------------------------------------------------------------------
    def loops(self, name: str) -> list[tuple[int, set[int], int, str]]:
        """Natural loops: (header, body blocks, header executions per entry K, source)."""
        blocks = self.graph(name)
        start = self._range(name)[0]
        dom = _dominators(blocks, start)
        back = [(b.addr, d) for b in blocks.values() for d, _c, _k in b.succ if d is not None and d in dom[b.addr]]
        bodies: dict[int, set[int]] = defaultdict(set)
        latches: dict[int, set[int]] = defaultdict(set)
        for u, h in back:
            bodies[h] |= _natural_loop(blocks, u, h)
            latches[h].add(u)
        _check_reducible(name, blocks, start, set(back))
        out = []
        for h, body in bodies.items():
            inner = set().union(*(b for h2, b in bodies.items() if h2 != h and h2 in body and b < body))
            n, where = self._loop_bound(name, blocks, h, body, inner)
            exits = {b for b in body for d, _c, _k in blocks[b].succ if d is None or d not in body}
            k = n if exits <= latches[h] else n + 1
            out.append((h, body, k, where))
        return out

    def _loop_bound(self, name, blocks, h, body, inner: set[int]) -> tuple[int, str]:
        """The bound of the innermost annotated source loop whose extent holds every source line
        of this loop's own instructions (those of loops nested in it aside), file by file; when
        several files qualify (inlined code), the largest bound (still a bound)."""
        by_file: dict[str, set[int]] = defaultdict(set)
        for b in body - inner:
            for ins in blocks[b].insns:
                where = self.lines.line_of(ins.addr)
                if where is not None:
                    by_file[where[0]].add(where[1])
        found = []
        for fname, lines in by_file.items():
            own = self._function_lines(fname, name)
            if own is not None and lines & own:
                lines = lines & own  # code inlined from other functions of the file is not the loop's

            fits = [(hi - lo, lo, n) for lo, hi, n in self.marks.get(fname, ()) if lo <= min(lines) and max(lines) <= hi]
            if fits:
                _size, lo, n = min(fits)
                found.append((n, f"{fname}:{lo}"))
        if not found:
            src = "; ".join(f"{f} lines {min(ls)}-{max(ls)}" for f, ls in sorted(by_file.items())) or "no line table"
            raise ToolError(f"{name}: loop at 0x{h:08x} ({src}) has no `wcet: loop bound N` annotation")
        return max(found)

    def _function_lines(self, fname: str, name: str) -> set[int] | None:
        """Lines of the definition of function `name` in source `fname`, if it is defined there."""
        key = (fname, name)
        if key not in self._extents:
            self._extents[key] = None
            path = self.sources / fname
            if path.is_file():
                lines = path.read_text().splitlines()
                head = re.compile(rf"^\S.*\b{re.escape(name)}\s*\(")
                for no, text in enumerate(lines, start=1):
                    if head.match(text) and not text.rstrip().endswith(";"):
                        opening = next(n for n in range(no, len(lines) + 1) if "{" in lines[n - 1])
                        self._extents[key] = set(range(no, _closing_line(lines, opening, fname) + 1))
                        break
        return self._extents[key]

    # --- the bound -------------------------------------------------------------------------
    def _bound(self, name: str) -> FunctionBound:
        blocks = self.graph(name)
        callees = sorted({b.call for b in blocks.values() if b.call})
        sub = {c: self.bound(c) for c in callees}
        loops = self.loops(name)
        start = self._range(name)[0]
        entry_s = entry_extra(self.dec.insn(start).cost, start)
        parts = self._art_extra(name, blocks, loops, start, sub)
        cycles = {}
        for table in TABLES:
            ideal = self._ipet(name, blocks, loops, start, lambda b, t=table: b.cost[t],
                               lambda _b, _d, c, _k, t=table: c[t], lambda b, t=table: sub[b.call].cycles[(t, "ideal")])
            base = ideal + (entry_s if table == "strict" else 0)
            cycles[(table, "ideal")] = base
            cycles[(table, "art")] = base + sum(parts.values())
        return FunctionBound(name, cycles, [(h, w, k) for h, _b, k, w in loops], callees, parts)

    def _ipet(self, name, blocks, loops, start, block_cost, edge_cost, call_cost) -> int:
        edges = [(None, start, 0.0)]  # the entry edge
        for b in blocks.values():
            for d, c, kind in b.succ:
                w = float(edge_cost(b, d, c, kind))
                if b.call is not None:
                    w += call_cost(b)
                if d is not None:
                    w += block_cost(blocks[d])
                edges.append((b.addr, d, w))
        edges[0] = (None, start, float(block_cost(blocks[start])))
        n = len(edges)
        idx_in, idx_out = defaultdict(list), defaultdict(list)
        for i, (u, v, _w) in enumerate(edges):
            if v is not None:
                idx_in[v].append(i)
            if u is not None:
                idx_out[u].append(i)
        rows, lo, hi = [], [], []
        entry = np.zeros(n)
        entry[0] = 1
        rows.append(entry), lo.append(1), hi.append(1)
        for a in blocks:
            r = np.zeros(n)
            r[idx_in[a]] += 1
            r[idx_out[a]] -= 1
            rows.append(r), lo.append(0), hi.append(0)
        for h, body, k, _where in loops:
            r = np.zeros(n)
            for i in idx_in[h]:
                u = edges[i][0]
                r[i] += 1 if (u is not None and u in body) else -(k - 1)
            rows.append(r), lo.append(-np.inf), hi.append(0)
        c = -np.array([w for _u, _v, w in edges])
        res = milp(c, constraints=LinearConstraint(np.array(rows), lo, hi), integrality=np.ones(n),
                   bounds=Bounds(0, np.inf))
        if res.status != 0:
            raise ToolError(f"{name}: longest-path programme failed ({res.message}); a loop without a bound?")
        return int(round(-res.fun))

    # --- art: flash wait states ------------------------------------------------------------
    def _art_extra(self, name, blocks, loops, start, sub) -> dict[str, int]:
        """Upper bounds of the flash stalls of one call, ART on and cold at the call, by source:
        code fetches, literal-pool reads, other reads from flash (0 when the image keeps no
        read-only data in flash)."""
        code, lits = self._footprint(name)
        out = {}
        for part, fits, per_block in (
                ("code", len(code) <= ART_I_LINES and WAIT_STATES * len(code), _code_lines),
                ("literal", len(lits) <= ART_D_LINES and WAIT_STATES * len(lits), _literal_reads),
                ("data", self.literals_only and 0, _other_reads)):
            if fits is not False:
                out[part] = int(fits)
                continue
            out[part] = self._scoped(name, blocks, loops, start, sub, part, per_block)
        return out

    def _scoped(self, name, blocks, loops, start, sub, part, per_block) -> int:
        """The function does not fit the cache as a whole: each outermost loop whose code (or
        literal lines) with its callees fits misses each of its lines at most once per entry
        (charged on its entry edges); every other block execution pays for each of its lines or
        reads, and a call from outside such a loop costs the callee's own bound of the part."""
        capacity = {"code": ART_I_LINES, "literal": ART_D_LINES}.get(part, 0)
        scopes: dict[int, tuple[set[int], int]] = {}
        for h, body, _k, _w in sorted(loops, key=lambda lp: -len(lp[1])):
            if capacity and not any(body <= b for b, _n in scopes.values()):
                lines = self._lines_of(blocks, body, part)
                if len(lines) <= capacity:
                    scopes[h] = (body, len(lines))
        covered = set().union(*(b for b, _n in scopes.values())) if scopes else set()

        def block_cost(b: _Block) -> int:
            return 0 if b.addr in covered else WAIT_STATES * per_block(b)

        def edge_cost(b: _Block, d, _c, kind) -> int:
            if d in scopes and b.addr not in scopes[d][0]:
                return WAIT_STATES * scopes[d][1]
            if part == "code" and kind in ("fall", "taken") and d not in covered and _first_line(blocks[d]) == _last_line(b):
                # d starts in the line b ends in: the ART's current instruction line, no miss
                # (RM0090 3.5.2). Not after a call: the callee may have evicted it.
                return -WAIT_STATES
            return 0

        def call_cost(b: _Block) -> int:
            return 0 if b.addr in covered else sub[b.call].art_parts[part]

        return self._ipet(name, blocks, loops, start, block_cost, edge_cost, call_cost)

    def _lines_of(self, blocks, body: set[int], part: str) -> set[int]:
        """Code lines (part "code") or literal lines of the blocks `body` and what they call."""
        out: set[int] = set()
        for a in body:
            b = blocks[a]
            if part == "code":
                out |= {x >> LINE_SHIFT for i in b.insns for x in range(i.addr, i.addr + i.size, 2)}
            else:
                out |= {literal_address(i) >> LINE_SHIFT for i in b.insns if words_read(i) and "pc" in i.cost.addr_regs}
            if b.call:
                code, lits = self._footprint(b.call)
                out |= code if part == "code" else lits
        return out

    def _footprint(self, name: str, seen: set[str] | None = None) -> tuple[set[int], set[int]]:
        """Flash code lines and literal-pool lines of a function and everything it calls."""
        seen = set() if seen is None else seen
        seen.add(name)
        code, lits = set(), set()
        for b in self.graph(name).values():
            for i in b.insns:
                code |= {a >> LINE_SHIFT for a in range(i.addr, i.addr + i.size, 2)}
                if words_read(i) and "pc" in i.cost.addr_regs:
                    lits.add(literal_address(i) >> LINE_SHIFT)
            if b.call and b.call not in seen:
                c, lt = self._footprint(b.call, seen)
                code |= c
                lits |= lt
        return code, lits


def _first_line(b: _Block) -> int:
    return b.insns[0].addr >> LINE_SHIFT


def _last_line(b: _Block) -> int:
    last = b.insns[-1]
    return (last.addr + last.size - 1) >> LINE_SHIFT


def _code_lines(b: _Block) -> int:
    return len({a >> LINE_SHIFT for i in b.insns for a in range(i.addr, i.addr + i.size, 2)})


def _literal_reads(b: _Block) -> int:
    return sum(words_read(i) for i in b.insns if "pc" in i.cost.addr_regs)


def _other_reads(b: _Block) -> int:
    """Reads whose address is neither PC- nor SP-relative: flash unless proved otherwise."""
    return sum(words_read(i) for i in b.insns if not {"pc", "sp"} & i.cost.addr_regs)


def _dominators(blocks: dict[int, _Block], start: int) -> dict[int, set[int]]:
    preds = defaultdict(set)
    for b in blocks.values():
        for d, _c, _k in b.succ:
            if d is not None:
                preds[d].add(b.addr)
    every = set(blocks)
    dom = {a: set(every) for a in blocks}
    dom[start] = {start}
    changed = True
    while changed:
        changed = False
        for a in blocks:
            if a == start:
                continue
            ps = [dom[p] for p in preds[a]]
            new = (set.intersection(*ps) if ps else set()) | {a}
            if new != dom[a]:
                dom[a], changed = new, True
    return dom


def _natural_loop(blocks, latch: int, header: int) -> set[int]:
    preds = defaultdict(set)
    for b in blocks.values():
        for d, _c, _k in b.succ:
            if d is not None:
                preds[d].add(b.addr)
    body, work = {header, latch}, [latch]
    while work:
        x = work.pop()
        if x == header:
            continue
        for p in preds[x]:
            if p not in body:
                body.add(p)
                work.append(p)
    return body


def _check_reducible(name, blocks, start, back: set) -> None:
    """Without its back edges the graph must be acyclic (else a loop has two entries)."""
    state: dict[int, int] = {}

    def visit(a: int) -> None:
        state[a] = 1
        for d, _c, _k in blocks[a].succ:
            if d is None or (a, d) in back:
                continue
            if state.get(d) == 1:
                raise ToolError(f"{name}: irreducible control flow at 0x{d:08x}: no static bound")
            if d not in state:
                visit(d)
        state[a] = 2

    visit(start)


def static_bound(elf: Path, sources: Path, entry: str) -> FunctionBound:
    """The bound of `entry` (and, memoised inside, of everything it calls)."""
    return Analysis(Image(elf), sources).bound(entry)
