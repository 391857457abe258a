"""benchmarks/ is a suite of scripts that each run on their own: no script imports another script
or a module of tests/, none edits ``sys.path`` or loads a file as a module, and no test loads a
benchmark (what both need lives in ``src/pedenv``). Read from the syntax trees, nothing is run."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
BENCHMARKS = REPO / "benchmarks"
TESTS = REPO / "tests"
#: Calls that load a file as a module, past the import system's search path.
FILE_LOADERS = {"spec_from_file_location", "SourceFileLoader", "run_path", "exec_module"}


def scripts() -> list[Path]:
    return sorted(BENCHMARKS.glob("*.py"))


def imported_roots(tree: ast.AST) -> set[str]:
    """The first component of every module an ``import`` names (relative imports as ``.``)."""
    roots = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            roots |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            roots.add("." if node.level else (node.module or "").split(".")[0])
    return roots


def path_edits_and_file_loads(tree: ast.AST) -> list[str]:
    """Every use of ``sys.path`` and every call of a file loader (:data:`FILE_LOADERS`), by line."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr == "path" and isinstance(node.value, ast.Name) \
                and node.value.id == "sys":
            found.append(f"line {node.lineno}: sys.path")
        elif isinstance(node, ast.Call):
            name = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
            if name in FILE_LOADERS:
                found.append(f"line {node.lineno}: {name}")
    return found


def local_names() -> set[str]:
    """Module names a benchmark could import from benchmarks/ or tests/ through ``sys.path``."""
    names = {p.stem for p in scripts()} | {p.stem for p in TESTS.rglob("*.py")}
    return names | {"tests", "benchmarks", "."}


def test_the_suite_has_scripts():
    assert len(scripts()) >= 10


@pytest.mark.parametrize("script", scripts(), ids=lambda p: p.name)
def test_a_benchmark_imports_only_installed_modules(script):
    tree = ast.parse(script.read_text(), filename=str(script))
    assert sorted(imported_roots(tree) & local_names()) == []
    assert path_edits_and_file_loads(tree) == []


@pytest.mark.parametrize("script", scripts(), ids=lambda p: p.name)
def test_a_benchmark_says_what_it_prints_and_runs_as_a_script(script):
    tree = ast.parse(script.read_text(), filename=str(script))
    assert ast.get_docstring(tree), f"{script.name}: no module docstring saying what it prints"
    guards = [n for n in tree.body if isinstance(n, ast.If) and "__main__" in ast.unparse(n.test)]
    assert guards, f"{script.name}: no `if __name__ == \"__main__\":`"


def test_no_test_loads_a_benchmark():
    bench = {p.stem for p in scripts()} | {"benchmarks"}
    helpers = {p.stem for p in TESTS.rglob("*.py")}
    bad = []
    for path in sorted(TESTS.rglob("*.py")):
        text = path.read_text()
        tree = ast.parse(text, filename=str(path))
        for root in sorted(imported_roots(tree) & (bench - helpers)):
            bad.append(f"{path.relative_to(REPO)}: imports {root}")
        bad += [f"{path.relative_to(REPO)} {hit}" for hit in path_edits_and_file_loads(tree)
                if "benchmarks" in text]
    assert bad == []


@pytest.mark.parametrize("source, problem", [
    ("import sys\nsys.path.insert(0, 'benchmarks')\n", "sys.path"),
    ("import importlib.util\nimportlib.util.spec_from_file_location('x', 'benchmarks/x.py')\n",
     "spec_from_file_location"),
])
def test_the_checks_see_a_path_edit_and_a_file_load(source, problem):
    assert [problem in hit for hit in path_edits_and_file_loads(ast.parse(source))] == [True]


def test_the_checks_see_an_import_of_a_script_or_a_test_module():
    tree = ast.parse("from run_real import main\nimport shared_paths\nfrom . import x\nimport numpy\n")
    assert sorted(imported_roots(tree) & local_names()) == [".", "run_real", "shared_paths"]
