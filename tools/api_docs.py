"""Render the API reference from the docstrings: every module of ``pedenv`` into ``docs/api/``.

Usage: ``python tools/api_docs.py [OUTPUT]`` (``make docs``). pdoc alone documents only what a
package's ``__all__`` names, so the modules are listed here from the source tree.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import pdoc

SRC = Path(__file__).resolve().parents[1] / "src"


def module_names() -> list[str]:
    """Every module and package under src/pedenv, dotted, sorted."""
    names = []
    for path in sorted((SRC / "pedenv").rglob("*.py")):
        parts = path.relative_to(SRC).with_suffix("").parts
        names.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return [n for n in names if not n.endswith("__main__")]


def main(argv: list[str]) -> int:
    output = Path(argv[0]) if argv else Path(__file__).resolve().parents[1] / "docs" / "api"
    pdoc.render.configure(docformat="restructuredtext", footer_text="pedenv")
    with warnings.catch_warnings():  # a package's page already lists its modules: no repeat warnings
        warnings.simplefilter("ignore", UserWarning)
        pdoc.pdoc(*module_names(), output_directory=output)
    pages = list(output.rglob("*.html"))
    print(f"{len(pages)} pages in {output}")
    return 0 if len(pages) > len(module_names()) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
