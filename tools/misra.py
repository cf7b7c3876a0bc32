"""MISRA C:2012 check of a unit's generated C: cppcheck with its MISRA addon (rule numbers only: the
rule texts are licensed and not shipped), findings grouped by rule, and each finding matched
against the documented deviations of docs/misra.md (a TOML block: rule, file pattern, reason).
A finding no deviation covers is "undocumented"; the goal is none."""
from __future__ import annotations

import fnmatch
import re
import shutil
import subprocess
import tempfile
import tomllib
from dataclasses import dataclass
from pathlib import Path

from codegen.unit import Unit
from tools.errors import ToolError

_LINE = re.compile(r"^(?P<file>[^:]+):(?P<line>\d+):(?P<id>[\w.-]+):(?P<msg>.*)$")
_DEVIATIONS = re.compile(r"```toml\n(.*?)```", re.S)


@dataclass(frozen=True)
class Finding:
    file: str
    line: int
    rule: str
    message: str


@dataclass(frozen=True)
class Deviation:
    rule: str
    files: str
    reason: str


def cppcheck() -> str:
    path = shutil.which("cppcheck")
    if path is None:
        raise ToolError("misra: 'cppcheck' not found on PATH (apt install cppcheck)")
    return path


def check(unit: Unit) -> list[Finding]:
    """cppcheck --addon=misra over the unit's C files (its headers included)."""
    with tempfile.TemporaryDirectory(prefix="staregen-misra-") as tmp:
        folder = Path(tmp)
        for name, text in unit.sources().items():
            (folder / name).write_text(text)
        sources = sorted(n for n in unit.sources() if n.endswith(".c"))
        cmd = [cppcheck(), "--addon=misra", "--std=c99", "--enable=style,warning,portability", "-q",
               "--template={file}:{line}:{id}:{message}", "-I", ".", *sources]
        res = subprocess.run(cmd, capture_output=True, text=True, cwd=folder, timeout=1800)
        findings = set()
        for raw in res.stderr.splitlines():
            m = _LINE.match(raw.strip())
            if m:
                findings.add(Finding(Path(m["file"]).name, int(m["line"]), m["id"], m["msg"].strip()))
        return sorted(findings, key=lambda f: (f.file, f.line, f.rule))


def load_deviations(doc: Path) -> list[Deviation]:
    """The ```toml blocks of docs/misra.md: [[deviation]] rule = "...", files = "glob", reason = "..."."""
    if not doc.is_file():
        return []
    out = []
    for block in _DEVIATIONS.findall(doc.read_text()):
        try:
            data = tomllib.loads(block)
        except tomllib.TOMLDecodeError as exc:
            raise ToolError(f"{doc}: a deviation block is not valid TOML: {exc}") from None
        for d in data.get("deviation", []):
            if not all(isinstance(d.get(k), str) and d.get(k) for k in ("rule", "files", "reason")):
                raise ToolError(f"{doc}: every deviation needs rule, files and reason")
            out.append(Deviation(d["rule"], d["files"], d["reason"]))
    return out


def undocumented(findings: list[Finding], deviations: list[Deviation]) -> list[Finding]:
    return [f for f in findings
            if not any(d.rule == f.rule and fnmatch.fnmatch(f.file, d.files) for d in deviations)]


def summary(kind: str, findings: list[Finding], deviations: list[Deviation]) -> list[str]:
    open_ = undocumented(findings, deviations)
    rules: dict[str, list[int]] = {}
    for f in findings:
        rules.setdefault(f.rule, [0, 0])[0] += 1
    for f in open_:
        rules[f.rule][1] += 1
    lines = [f"### Unit `{kind}`: {len(findings)} findings, {len(open_)} undocumented", "",
             "| rule / check | findings | undocumented |", "|---|---:|---:|"]
    lines += [f"| `{r}` | {n} | {u} |" for r, (n, u) in sorted(rules.items(), key=lambda kv: (-kv[1][0], kv[0]))]
    return lines + [""]
