"""The shape of the code under ``src/pedenv``, measured from its syntax trees.

Prints, against the layout goals of the project:

- functions longer than ``--max-lines`` (60) lines, and CLI command functions (in ``cli/``,
  decorated with ``@app.command``) whose body is longer than ``--max-command-lines`` (30);
- functions with more than ``--max-params`` (8) parameters (``self``/``cls`` not counted; a CLI
  command's own options excepted);
- each folder's share of the package's lines (goal: none above one sixth);
- cycles among the sub-packages (and top-level modules): an arrow back up;
- arrows from the core (``model.py``, ``config*.py``, ``tracking/``, ``localization/``) to the
  pose network (``pose/``) or the detection stage (``detection/``): the core takes detections
  whatever made them.

Usage: ``python tools/code_shape.py [--check]``; ``--check`` exits 1 when a goal is missed.
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections import defaultdict
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "pedenv"


def _is_command(node: ast.AST) -> bool:
    for deco in getattr(node, "decorator_list", []):
        target = deco.func if isinstance(deco, ast.Call) else deco
        if isinstance(target, ast.Attribute) and target.attr == "command":
            return True
    return False


def _params(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    args = node.args
    names = [a.arg for a in args.posonlyargs + args.args + args.kwonlyargs]
    names += [a.arg for a in (args.vararg, args.kwarg) if a is not None]
    return len([n for n in names if n not in ("self", "cls")])


def _body_lines(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines of the body after the docstring."""
    body = node.body
    if body and isinstance(body[0], ast.Expr) and isinstance(getattr(body[0], "value", None), ast.Constant) \
            and isinstance(body[0].value.value, str) and len(body) > 1:
        body = body[1:]
    return (node.end_lineno or node.lineno) - body[0].lineno + 1


def functions(root: Path = PACKAGE):
    """(module path, name, lines, body lines, parameters, is a CLI command) of every function."""
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = (node.end_lineno or node.lineno) - node.lineno + 1
                yield path.relative_to(root), node.name, lines, _body_lines(node), _params(node), _is_command(node)


def folder_lines(root: Path = PACKAGE) -> dict[str, int]:
    """Lines per top-level folder of the package ('.' for modules at its top)."""
    counts: dict[str, int] = defaultdict(int)
    for path in root.rglob("*.py"):
        rel = path.relative_to(root)
        counts[rel.parts[0] if len(rel.parts) > 1 else "."] += len(path.read_text().splitlines())
    return dict(counts)


def package_arrows(root: Path = PACKAGE) -> set[tuple[str, str]]:
    """(importing sub-package, imported sub-package) pairs; top-level modules count as their own name."""
    arrows = set()
    for path in root.rglob("*.py"):
        rel = path.relative_to(root)
        source = rel.parts[0] if len(rel.parts) > 1 else rel.stem
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("pedenv."):
                names = [node.module]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names if a.name.startswith("pedenv.")]
            for name in names:
                target = name.split(".")[1]
                if target != source:
                    arrows.add((source, target))
    return arrows


#: The core and what it must not import.
CORE = ("model", "config", "config_position", "config_tracking", "tracking", "localization")
ABOVE_CORE = ("pose", "detection")


def package_cycles(arrows: set[tuple[str, str]]) -> list[list[str]]:
    """Groups of more than one sub-package that reach each other through ``arrows``, each sorted."""
    graph: dict[str, set[str]] = defaultdict(set)
    for a, b in arrows:
        graph[a].add(b)
    reach: dict[str, set[str]] = {}
    for start in {n for arrow in arrows for n in arrow}:
        seen, todo = set(), [start]
        while todo:
            for nxt in graph[todo.pop()] - seen:
                seen.add(nxt)
                todo.append(nxt)
        reach[start] = seen
    groups = {tuple(sorted({n} | {m for m in reach[n] if n in reach[m]})) for n in reach}
    return sorted(list(g) for g in groups if len(g) > 1)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-lines", type=int, default=60)
    parser.add_argument("--max-command-lines", type=int, default=30)
    parser.add_argument("--max-params", type=int, default=8)
    parser.add_argument("--check", action="store_true", help="exit 1 when a goal is missed")
    args = parser.parse_args(argv)

    missed = 0
    rows = list(functions())
    long = [r for r in rows if not r[5] and r[2] > args.max_lines]
    long_commands = [r for r in rows if r[5] and r[3] > args.max_command_lines]
    many = [r for r in rows if not r[5] and r[4] > args.max_params]
    for title, found, col in ((f"functions over {args.max_lines} lines", long, 2),
                              (f"commands with a body over {args.max_command_lines} lines", long_commands, 3),
                              (f"functions with more than {args.max_params} parameters", many, 4)):
        print(f"{title}: {len(found)}")
        for path, name, *values, _ in sorted(found, key=lambda r: -r[col]):
            print(f"  {path}:{name}  {values[col - 2]}")
        missed += len(found)

    counts = folder_lines()
    total = sum(counts.values())
    print(f"lines per folder (package: {total}; goal: none above {total / 6:.0f}, one sixth):")
    for name, n in sorted(counts.items(), key=lambda kv: -kv[1]):
        flag = "  <- above one sixth" if name != "." and n > total / 6 else ""
        missed += bool(flag)
        print(f"  {name:<14}{n:>6}  {100 * n / total:5.1f} %{flag}")

    arrows = package_arrows()
    cycles = package_cycles(arrows)
    print(f"cycles among sub-packages: {len(cycles)}")
    for group in cycles:
        print(f"  {' <-> '.join(group)}")
    missed += len(cycles)
    up = sorted(a for a in arrows if a[0] in CORE and a[1] in ABOVE_CORE)
    print(f"core modules importing {' or '.join(ABOVE_CORE)}: {len(up)}")
    for a, b in up:
        print(f"  {a} -> {b}")
    missed += len(up)
    return 1 if (args.check and missed) else 0


if __name__ == "__main__":
    sys.exit(main())
