"""The package's layout: no module imports a module that imports it back, and the
module map (docs/modules.md) names every module of the tree."""

from __future__ import annotations

import ast
import re
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
MODULE_MAP = Path(__file__).resolve().parents[1] / "docs" / "modules.md"


def module_name(path: Path) -> str:
    parts = path.relative_to(SRC).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_graph() -> dict[str, set[str]]:
    """Module -> the pedenv modules it imports anywhere (function-level imports too)."""
    modules = {module_name(p): p for p in SRC.rglob("*.py")}
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    base = ".".join(
                        package.split(".")[: len(package.split(".")) - node.level + 1] + ([base] if base else [])
                    )
                targets |= {f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names}
        graph[name] = {t for t in targets if t in modules and t != name}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (scipy's csgraph)."""
    import numpy as np
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components

    names = sorted(graph)
    position = {n: i for i, n in enumerate(names)}
    edges = [(position[v], position[w]) for v in names for w in graph[v]]
    rows, cols = (np.array(side, int) for side in zip(*edges)) if edges else (np.zeros(0, int), np.zeros(0, int))
    matrix = csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(names), len(names)))
    _, labels = connected_components(matrix, directed=True, connection="strong")
    groups = [[n for n, label in zip(names, labels) if label == k] for k in sorted(set(labels))]
    return sorted(group for group in groups if len(group) > 1)


def test_the_graph_sees_imports():
    graph = import_graph()
    assert "pedenv.tracking.tracker" in graph["pedenv.model"]
    assert "pedenv.localization.base" in graph["pedenv.localization.paper"]


def test_no_module_imports_a_module_that_imports_it_back():
    assert cycles(import_graph()) == []


def test_module_map_matches_the_tree():
    """Every module and package of src/pedenv is named in the module map (docs/modules.md),
    and the map names nothing that does not exist."""
    block = MODULE_MAP.read_text()
    named = {
        n
        for n in re.findall(r"`((?:[a-z0-9_]+/)*[a-z0-9_]+(?:\.py|/))`", block)
        if not n.startswith(("src/", "tests/"))
    }
    tree = {str(p.relative_to(SRC / "pedenv")) for p in (SRC / "pedenv").rglob("*.py") if p.name != "__init__.py"}
    tree |= {str(p.relative_to(SRC / "pedenv")) + "/" for p in (SRC / "pedenv").rglob("*") if p.is_dir()
             and (p / "__init__.py").exists()}
    assert sorted(tree - named) == []
    assert sorted(named - tree) == []


def package_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """Sub-package (or top-level module) -> those it imports: ``pedenv.detection.redetect`` counts as
    ``pose``, ``pedenv.config`` as ``config``; the package root ``pedenv`` itself is left out."""
    def part(module: str) -> str | None:
        names = module.split(".")
        return names[1] if len(names) > 1 else None

    packages: dict[str, set[str]] = {}
    for module, targets in graph.items():
        source = part(module)
        if source is not None:
            packages.setdefault(source, set()).update(t for t in map(part, targets) if t not in (None, source))
    return packages


def test_no_sub_package_imports_one_that_imports_it_back():
    """Not only modules: the sub-packages (and top-level modules) form no cycle either, so every
    arrow between them runs one way (``detection`` takes the network from ``pose``, never back)."""
    packages = package_graph(import_graph())
    assert "pose" in packages["detection"] and "detection" not in packages["pose"]
    assert cycles(packages) == []


#: The core: the model and what it is made of. It takes detections whatever made them.
CORE = ("model", "config", "config_position", "config_tracking", "tracking", "localization")


def test_the_core_imports_nothing_of_the_network_or_the_detection_stage():
    """``model.py``, ``config*.py``, ``tracking/`` and ``localization/`` import nothing from ``pose/``
    or ``detection/`` (the detection settings are registered into the run's config from above)."""
    packages = package_graph(import_graph())
    assert {part: sorted(packages[part] & {"pose", "detection"}) for part in CORE} == {part: [] for part in CORE}
