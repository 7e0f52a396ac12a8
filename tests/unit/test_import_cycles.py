"""No import cycle among hugomap's modules.

Every ``import`` and ``from ... import`` in ``src/hugomap/**/*.py`` is read with ``ast``,
wherever it stands (module level, inside functions, under ``if TYPE_CHECKING``), and becomes
an edge to the hugomap module it loads: ``from .a import b`` loads ``a`` and, where ``b`` is
a module, ``a.b``; importing ``a.b`` loads the package ``a`` first. A cycle among these edges
fails the test, with its modules. Run as a script (``python tests/unit/test_import_cycles.py``)
it prints the cycles, or that there are none.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src"
PACKAGE = "hugomap"


def _modules() -> dict[str, Path]:
    """Module name -> file, for every module and package of hugomap."""
    out = {}
    for f in sorted((SRC / PACKAGE).rglob("*.py")):
        parts = list(f.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = f
    return out


def _with_parents(name: str, known: dict[str, Path]) -> set[str]:
    """``name`` and the packages above it (their ``__init__`` runs first), if hugomap's."""
    parts = name.split(".")
    return {".".join(parts[:i]) for i in range(1, len(parts) + 1)} & set(known)


def import_graph() -> dict[str, set[str]]:
    """Module -> the hugomap modules its import statements load (itself excluded)."""
    known = _modules()
    graph: dict[str, set[str]] = {}
    for name, path in known.items():
        is_pkg = path.name == "__init__.py"
        here = name if is_pkg else name.rpartition(".")[0]  # the package of relative imports
        edges: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    edges |= _with_parents(alias.name, known)
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = here.split(".")
                    base = base[: len(base) - (node.level - 1)]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                edges |= _with_parents(target, known)
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    if sub in known:
                        edges |= _with_parents(sub, known)
        graph[name] = edges - {name}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []
    counter = 0

    def visit(v: str) -> None:
        nonlocal counter
        index[v] = low[v] = counter
        counter += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def test_no_import_cycle() -> None:
    found = cycles(import_graph())
    assert not found, "import cycles among hugomap's modules: " + "; ".join(
        " <-> ".join(c) for c in found
    )


def test_the_graph_sees_function_level_imports() -> None:
    """The check is not vacuous: function-level imports are edges (cli imports pipeline
    inside main), and a cycle made by hand is found."""
    graph = import_graph()
    assert "hugomap.stages" in graph["hugomap.cli"]
    assert "hugomap.config" in graph["hugomap.status"]
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_config_imports_nothing_above_it() -> None:
    """What validation loads (it runs when Snakemake parses the workflow) reaches neither
    the campaign's dataset nor status, io or any solver module: only the registry, which
    names the backends' scene-config modules by string and imports them when asked, and the
    cost laws (a JSON reader) that ``schemes: [auto]`` is resolved from."""
    graph = import_graph()
    reach, todo = set(), ["hugomap.config"]
    while todo:
        for w in graph[todo.pop()] - reach:
            reach.add(w)
            todo.append(w)
    assert reach == {"hugomap", "hugomap.campaign_expand", "hugomap.cost_laws", "hugomap.keys",
                     "hugomap.registry"}  # fmt: skip


def test_particle_backends_stand_side_by_side() -> None:
    """The two particle backends share ``hugomap.particles`` and do not import each other:
    no module of ``lammps`` imports ``md`` (its lj/cut reference is asked of the registry's
    ``solver: md`` backend, by name), none of ``md`` imports ``lammps``, and ``particles``
    imports neither."""

    def under(module: str, package: str) -> bool:
        return module == package or module.startswith(package + ".")

    graph = import_graph()
    for src, banned in [("hugomap.lammps", ("hugomap.md",)),
                        ("hugomap.md", ("hugomap.lammps",)),
                        ("hugomap.particles", ("hugomap.md", "hugomap.lammps"))]:  # fmt: skip
        found = sorted(
            f"{m} -> {w}"
            for m, edges in graph.items()
            if under(m, src)
            for w in edges
            if any(under(w, b) for b in banned)
        )
        assert not found, f"{src} imports {banned}: " + "; ".join(found)
    assert any(under(w, "hugomap.particles") for w in graph["hugomap.lammps.backend"])
    assert any(under(w, "hugomap.particles") for w in graph["hugomap.md.backend"])


if __name__ == "__main__":
    found = cycles(import_graph())
    for c in found:
        print("cycle:", " <-> ".join(c))
    print(f"{len(import_graph())} modules, {len(found)} import cycle(s)")
    sys.exit(1 if found else 0)
