"""Structural coverage of a unit's generated C under its own gate vectors (gcc --coverage, gcov's
JSON): branches and lines per file, and every branch never taken, for docs/coverage.md.

The unit's sources are built for x86-64 with the flight flags at -O0 (one object branch per
source branch, nothing folded away) plus --coverage, into a small executable that reads records
on stdin: independent steps ({state; input} -> {output; state}) and, for a stateful unit, its
gate sequences from init with the state carried in the C.
"""
from __future__ import annotations

import gzip
import json
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from codegen.unit import Unit
from firmware.flags import COMMON, with_opt
from tools.errors import ToolError
from tools.fuzz import harness_source
from tools.runners import LAYOUT_FILE, layout_source, pack

COVERAGE_FLAGS = ["--coverage", "-fprofile-update=single"]


@dataclass
class FileCoverage:
    lines: int = 0
    lines_hit: int = 0
    branches: int = 0
    branches_taken: int = 0
    untaken: list[tuple[int, int]] = field(default_factory=list)   # (line, branch index on that line)


@dataclass
class CoverageReport:
    unit: str
    vectors: int
    files: dict[str, FileCoverage]
    unused: list[str] = field(default_factory=list)   # shared-library functions the unit never runs

    @property
    def branches(self) -> tuple[int, int]:
        return (sum(f.branches_taken for f in self.files.values()), sum(f.branches for f in self.files.values()))


def _sequence_harness(unit: Unit) -> str:
    """Inputs only on stdin, the state carried from <entry>_init; outputs on stdout."""
    i_sz, o_sz = unit.input_dtype.itemsize, unit.output_dtype.itemsize
    return f"""
int sg_cov_sequence(void);
int sg_cov_sequence(void)
{{
    {unit.c_types['state']} state;
    unsigned char a[{i_sz}], b[{o_sz}];
    {unit.init_symbol}(&state);
    while (fread(a, sizeof a, 1u, stdin) == 1u) {{
        {unit.step_symbol}(&state, (const void *)a, (void *)b);
        if (fwrite(b, sizeof b, 1u, stdout) != 1u) {{
            return 3;
        }}
    }}
    return 0;
}}
"""


def build(unit: Unit, folder: Path) -> Path:
    if shutil.which("gcc") is None or shutil.which("gcov") is None:
        raise ToolError("coverage: gcc and gcov are needed")
    main = harness_source(unit)
    if unit.stateful:   # `cov seq` runs the sequence loop instead of independent records
        main = main.replace("int main(void)\n{", _sequence_harness(unit) + "\nint main(int argc, char **argv)\n{\n"
                            "    if (argc > 1) {\n        (void)argv;\n        return sg_cov_sequence();\n    }", 1)
    files = {**unit.sources(), LAYOUT_FILE: layout_source(unit), "cov_main.c": main}
    for name, text in files.items():
        (folder / name).write_text(text)
    exe = folder / "cov"
    objects = []
    for name in sorted(n for n in files if n.endswith(".c")):   # one object each: <name>.gcno / .gcda
        obj = folder / (name[:-2] + ".o")
        compile_in(["gcc", *with_opt(COMMON, "-O0"), *COVERAGE_FLAGS, "-I", str(folder), "-c", name, "-o", obj.name],
                 folder)
        objects.append(obj.name)
    compile_in(["gcc", *COVERAGE_FLAGS, *objects, "-o", exe.name], folder)
    return exe


def compile_in(cmd: list[str], folder: Path) -> None:
    res = subprocess.run(cmd, capture_output=True, text=True, cwd=folder)
    if res.returncode != 0:
        first = next((ln for ln in res.stderr.splitlines() if "error" in ln), res.stderr.strip()[:200])
        raise ToolError(f"coverage: build failed: {first}")


def _run(exe: Path, data: bytes, *args: str) -> bytes:
    res = subprocess.run([str(exe), *args], input=data, capture_output=True, cwd=exe.parent, timeout=3600)
    if res.returncode != 0:
        raise ToolError(f"coverage: the instrumented build exited with {res.returncode}")
    return res.stdout


def run_words(exe: Path, data: bytes) -> np.ndarray:
    """The instrumented build's stdout as 32-bit words."""
    return np.frombuffer(_run(exe, data), dtype=np.uint32)


LIBRARY = ("sg_math.c", "sg_math.h")   # shared: only the functions the unit runs count


def gcov_counts(folder: Path, objects: list[str], files: list[str]) -> tuple[dict[str, FileCoverage], list[str]]:
    """Line and branch counts of `files`, summed over every object (a header's inline code appears in
    each object that includes it); in the shared library, functions never run are left out and
    returned by name."""
    res = subprocess.run(["gcov", "--json-format", "--branch-probabilities", *objects], capture_output=True,
                         text=True, cwd=folder)
    if res.returncode != 0:
        raise ToolError(f"coverage: gcov failed: {res.stderr.strip()[:200]}")
    lines: dict[tuple[str, int], int] = {}
    branches: dict[tuple[str, int, int], int] = {}
    functions: dict[tuple[str, str], list] = {}
    for path in sorted(folder.glob("*.gcov.json.gz")):
        doc = json.loads(gzip.decompress(path.read_bytes()))
        for f in doc["files"]:
            name = Path(f["file"]).name
            if name not in files:
                continue
            for fn in f.get("functions", []):
                entry = functions.setdefault((name, fn["name"]), [fn["start_line"], fn["end_line"], 0])
                entry[2] += fn["execution_count"]
            for line in f["lines"]:
                key = (name, line["line_number"])
                lines[key] = lines.get(key, 0) + line["count"]
                for k, br in enumerate(line.get("branches", [])):
                    if not br.get("throw"):
                        bkey = (name, line["line_number"], k)
                        branches[bkey] = branches.get(bkey, 0) + br["count"]
    unused = sorted({fn for (name, fn), (_, _, count) in functions.items() if name in LIBRARY and count == 0})

    def counted(name: str, number: int) -> bool:
        if name not in LIBRARY:
            return True
        return not any(n == name and a <= number <= b and c == 0 for (n, _), (a, b, c) in functions.items())

    out: dict[str, FileCoverage] = {}
    for (name, number), count in sorted(lines.items()):
        if counted(name, number):
            cov = out.setdefault(name, FileCoverage())
            cov.lines += 1
            cov.lines_hit += count > 0
    for (name, number, k), count in sorted(branches.items()):
        if counted(name, number):
            cov = out.setdefault(name, FileCoverage())
            cov.branches += 1
            if count > 0:
                cov.branches_taken += 1
            else:
                cov.untaken.append((number, k))
    return out, unused


def measure(unit: Unit, n: int = 20_000, n_seq: int = 4, steps: int = 500, seed: int = 0) -> CoverageReport:
    """Coverage of the unit's own C files (sg_math included) under its gate classes and sequences."""
    with tempfile.TemporaryDirectory(prefix="staregen-cov-") as tmp:
        folder = Path(tmp)
        exe = build(unit, folder)
        classes = unit.gate_classes(n, seed)
        total = 0
        for batch in classes.values():
            if batch.input.shape[0]:
                _run(exe, pack(unit, batch).tobytes())
                total += batch.input.shape[0]
        if unit.stateful and n_seq:
            seqs = unit.gate_sequences(n_seq, steps, seed + 1)
            for s in range(seqs.shape[0]):
                _run(exe, np.ascontiguousarray(seqs[s]).tobytes(), "seq")
                total += seqs.shape[1]
        objects = sorted(name[:-2] + ".o" for name in unit.sources() if name.endswith(".c"))
        files, unused = gcov_counts(folder, objects, sorted(unit.sources()))
        return CoverageReport(unit.kind, total, files, unused)


def report_lines(rep: CoverageReport, source_text: dict[str, str]) -> list[str]:
    """Markdown: per file lines and branches, then every untaken branch with its source line."""
    taken, total = rep.branches
    lines = [f"### Unit `{rep.unit}` — {rep.vectors} steps: branches {taken}/{total} "
             f"({100.0 * taken / max(total, 1):.1f} %)", "",
             "| file | lines hit | branches taken |", "|---|---:|---:|"]
    for name, f in rep.files.items():
        lines.append(f"| `{name}` | {f.lines_hit}/{f.lines} | {f.branches_taken}/{f.branches} |")
    lines.append("")
    if rep.unused:
        lines += [f"Library functions not run by this unit (left out): {', '.join(rep.unused)}.", ""]
    for name, f in rep.files.items():
        text = source_text.get(name, "").splitlines()
        for line, k in f.untaken:
            code = text[line - 1].strip() if 0 < line <= len(text) else ""
            lines.append(f"- `{name}:{line}` branch {k}: `{code[:100]}`")
    return lines
