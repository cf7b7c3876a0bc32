"""The layering of docs/architecture.md, checked over the tree's imports (ast, every import
statement, also those inside functions): codegen imports none of firmware/tools/host; firmware may
import codegen; tools may import firmware and codegen; host may import all three. And no import
cycle among the project's modules, function-local imports included."""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LAYERS = {"codegen": 0, "firmware": 1, "tools": 2, "host": 3}


def module_name(path: Path) -> str:
    parts = list(path.with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def tree_sources(root: Path = ROOT) -> dict[str, str]:
    """{module: source} of every Python file of the four layers."""
    return {module_name(p.relative_to(root)): p.read_text(encoding="utf-8")
            for layer in LAYERS for p in sorted((root / layer).rglob("*.py"))}


def imports(module: str, source: str, known: set[str]) -> set[str]:
    """Project modules `module` imports (absolute or relative), resolved to the deepest known module."""
    found = set()
    is_package = any(k.startswith(module + ".") for k in known)
    package = module if is_package else module.rsplit(".", 1)[0]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            # `from pkg import sub` runs pkg/__init__ and pkg/sub; only the module is the dependency
            names = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
        else:
            continue
        for name in names:
            while name and name not in known:
                name = name.rpartition(".")[0]
            if name and name != module:
                found.add(name)
    return found


def graph(sources: dict[str, str]) -> dict[str, set[str]]:
    known = set(sources)
    return {m: imports(m, s, known) for m, s in sources.items()}


def upward_imports(g: dict[str, set[str]]) -> list[str]:
    return sorted(f"{m} -> {t}" for m, targets in g.items() for t in targets
                  if LAYERS[t.split(".")[0]] > LAYERS[m.split(".")[0]])


def cycles(g: dict[str, set[str]]) -> list[list[str]]:
    """Every strongly connected component with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in g.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(g):
        if v not in index:
            visit(v)
    return out


def test_no_layer_imports_a_higher_one():
    assert upward_imports(graph(tree_sources())) == []


def test_no_import_cycles_even_through_function_local_imports():
    assert cycles(graph(tree_sources())) == []


def test_the_checks_fail_on_a_planted_upward_import_and_a_planted_cycle():
    sources = tree_sources()
    planted = dict(sources)
    planted["codegen.artifact"] = sources["codegen.artifact"] + "\n\ndef f():\n    from host.cli import main\n"
    assert upward_imports(graph(planted)) == ["codegen.artifact -> host.cli"]
    planted = dict(sources)
    planted["codegen.errors"] = sources["codegen.errors"] + "\nfrom codegen import artifact\n"
    # the planted cycle's component holds both (and whatever else lies on a path between them)
    assert any({"codegen.artifact", "codegen.errors"} <= set(c) for c in cycles(graph(planted)))


def test_the_top_level_stays_that_of_the_readme():
    top = {p.name for p in ROOT.iterdir() if p.is_dir() and not p.name.startswith(".")} - {"out", "build"}
    assert {"codegen", "firmware", "host", "tests", "tools"} <= top
    assert not {n for n in top if not n.endswith(".egg-info") and n != "__pycache__"} - {
        "codegen", "firmware", "host", "tests", "tools", "docs"}
