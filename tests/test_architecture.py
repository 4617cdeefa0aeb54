"""The import graph of evalsuite, renderers and study_app: no cycles between modules, and layers only
import downwards. Read from the source with ``ast`` (imports under ``if TYPE_CHECKING:`` do not count)."""
from __future__ import annotations

import ast
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("evalsuite", "renderers", "study_app")

# Lower layers first; a module may import from its own layer's package or any layer below it.
LAYERS = [
    {"evalsuite._version", "evalsuite.errors", "evalsuite.hashing", "evalsuite.audio", "evalsuite.parallel",
     "evalsuite.contracts", "evalsuite.registry"},
    {"evalsuite.motion"},
    {"evalsuite.corpus"},
    {"evalsuite.metrics", "evalsuite.features"},
    {"evalsuite.synth", "evalsuite.learned", "evalsuite.analysis", "renderers", "evalsuite.critic"},
    {"evalsuite.generators", "study_app", "evalsuite.leaderboard"},
    {"evalsuite.cli", "evalsuite.demo", "evalsuite.pipeline", "evalsuite.score_command", "evalsuite.validity",
     "evalsuite.__main__", "evalsuite"},
]


def _module_name(path: pathlib.Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _type_checking_lines(tree: ast.AST) -> set[int]:
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for sub in node.body:
                lines.update(range(sub.lineno, (sub.end_lineno or sub.lineno) + 1))
    return lines


def import_graph() -> dict[str, set[str]]:
    modules = {_module_name(p): p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py")}
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for name, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        skip = _type_checking_lines(tree)
        is_pkg = path.name == "__init__.py"
        for node in ast.walk(tree):
            if getattr(node, "lineno", None) in skip:
                continue
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    pkg = name.split(".") if is_pkg else name.split(".")[:-1]
                    pkg = pkg[: len(pkg) - node.level + 1]
                    base = ".".join(pkg + ([base] if base else []))
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
            for t in targets:
                while t and t not in modules:
                    t = t.rpartition(".")[0]
                if t and t != name:
                    graph[name].add(t)
    return graph


def _layer(module: str) -> int:
    best, index = -1, -1
    for i, layer in enumerate(LAYERS):
        for prefix in layer:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best:
                best, index = len(prefix), i
    return index


def _strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
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

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def _without_package_reexports(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """A package's ``__init__`` re-exporting its own submodules is not a cycle between modules."""
    return {m: {t for t in deps if not (t.startswith(m + ".") or m.startswith(t + ".") and
                                        _is_init_of(t, m))} for m, deps in graph.items()}


def _is_init_of(package: str, module: str) -> bool:
    return (ROOT / package.replace(".", "/") / "__init__.py").exists() and module.startswith(package + ".")


def test_every_module_is_in_a_layer():
    unplaced = sorted(m for m in import_graph() if _layer(m) < 0)
    assert unplaced == []


def test_no_import_cycles_between_modules():
    cycles = _strongly_connected(_without_package_reexports(import_graph()))
    assert cycles == []


def test_layers_import_only_downwards():
    upward = sorted(f"{m} -> {t}" for m, deps in import_graph().items() for t in deps
                    if _layer(t) > _layer(m))
    assert upward == []


def test_the_metrics_package_imports_nothing_from_learned():
    graph = import_graph()
    assert sorted(t for m, deps in graph.items() if m.startswith("evalsuite.metrics")
                  for t in deps if t.startswith("evalsuite.learned")) == []


def test_corpora_are_read_without_metrics_and_the_synthetic_speaker_is_not_a_reader():
    """Reading a corpus needs no metric, and no reader depends on the synthetic speaker that writes corpora: the
    corpus package sits below metrics and features, the speaker above them (it measures its own speech)."""
    graph = import_graph()
    upward = sorted(f"{m} -> {t}" for m, deps in graph.items() if m.startswith("evalsuite.corpus")
                    for t in deps if t.startswith(("evalsuite.metrics", "evalsuite.features", "evalsuite.synth")))
    assert upward == []


def test_no_module_is_a_god_file():
    long = sorted(f"{p.relative_to(ROOT)}: {n}" for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py")
                  if (n := len(p.read_text(encoding="utf-8").splitlines())) > 350)
    assert long == []
