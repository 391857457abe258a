"""The docs state today's truth in pages a reader can take in: every topic document of docs/ is
at most 250 lines (the history lives in the one dated log, docs/measurement_log.md), every one
is reachable from the README or docs/results.md, and no machine's own paths appear in the
sources, the docs or the README, and the docs point at no file outside the repository but the
shared samples."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
LOG = DOCS / "measurement_log.md"
MAX_LINES = 250
#: An absolute path on a developer's or CI machine: a root folder of the usual places, not
#: preceded by a name character (``apps/options.py`` is not ``/opt``).
MACHINE_PATH = re.compile(r"(?<![\w.~/-])/(work|root|home|tmp|opt)(/|\b)")
#: A file outside the repository: a ``../`` path anywhere but the shared samples, or the shared notes.
OUTSIDE = re.compile(r"(?<!\.)\.\./(?!shared/samples)[\w.]|\bFORMATS\.md\b|\bSTYLE\.md\b")
#: A link to a document of docs/: ``(docs/x.md)`` from the README, ``(x.md)`` from docs/.
LINK = re.compile(r"\]\((?:docs/)?([\w-]+\.md)(?:#[\w-]*)?\)")


def topic_docs() -> list[Path]:
    return sorted(p for p in DOCS.glob("*.md") if p != LOG)


def machine_paths(text: str) -> list[str]:
    return [m.group(0) for m in MACHINE_PATH.finditer(text)]


def test_there_is_one_dated_log():
    dated = re.findall(r"(?m)^## (\d{4}-\d{2}-\d{2})$", LOG.read_text())
    assert dated and dated == sorted(dated)


@pytest.mark.parametrize("doc", topic_docs(), ids=lambda p: p.name)
def test_a_topic_document_is_at_most_250_lines(doc):
    assert len(doc.read_text().splitlines()) <= MAX_LINES


def test_every_document_is_linked_from_the_readme_or_the_results():
    linked = set(LINK.findall((REPO / "README.md").read_text())) | set(LINK.findall((DOCS / "results.md").read_text()))
    assert sorted({p.name for p in DOCS.glob("*.md")} - linked - {"results.md"}) == []
    assert "results.md" in LINK.findall((REPO / "README.md").read_text())


def test_no_machine_path_in_the_sources_the_docs_or_the_readme():
    files = [REPO / "README.md", *DOCS.glob("*.md"), *(REPO / "src").rglob("*.py")]
    found = {str(p.relative_to(REPO)): hits for p in files if (hits := machine_paths(p.read_text()))}
    assert found == {}


def test_the_docs_refer_to_no_file_outside_the_repository_but_the_samples():
    files = [REPO / "README.md", *DOCS.glob("*.md")]
    found = {str(p.relative_to(REPO)): hits for p in files if (hits := OUTSIDE.findall(p.read_text()))}
    assert found == {}


@pytest.mark.parametrize("text, hits", [
    ("PYTHONPATH=/work/main/src python x.py", ["/work/"]),
    ("written to /tmp/det-far.npz", ["/tmp/"]),
    ("`apps/options.py`, ~/.cache/pedenv, ../shared/samples/real, /proc/nope", []),
])
def test_the_path_check_tells_machine_paths_from_module_names(text, hits):
    assert machine_paths(text) == hits


@pytest.mark.parametrize("text, hits", [
    ("layout in ../shared/FORMATS.md", 2),
    ("python x.py --samples ../shared/samples/real; .../scenes/<scene>/result.npz", 0),
    ("see ../other/notes.txt", 1),
])
def test_the_outside_check_allows_only_the_shared_samples(text, hits):
    assert len(OUTSIDE.findall(text)) == hits
