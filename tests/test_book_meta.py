"""Hygiene of the book: table of contents, stored notebooks, no unfinished text."""

import json
import re
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
BOOK = ROOT / "book"


def toc_entries():
    """The documents listed in _toc.yml (root and every `file:` entry), in order."""
    toc = yaml.safe_load((ROOT / "_toc.yml").read_text())
    entries = [toc["root"]]

    def walk(node):
        if isinstance(node, dict):
            if "file" in node:
                entries.append(node["file"])
            for key in ("parts", "chapters", "sections"):
                for child in node.get(key, ()):
                    walk(child)

    walk(toc)
    return entries


def toc_files():
    """The documents listed in _toc.yml, without suffix."""
    return {entry.removesuffix(".md").removesuffix(".ipynb") for entry in toc_entries()}


def book_documents():
    return {str(p.relative_to(ROOT).with_suffix(""))
            for p in BOOK.rglob("*") if p.suffix in {".md", ".ipynb"}
            and ".ipynb_checkpoints" not in p.parts}


NOTEBOOKS = sorted(BOOK.glob("*.ipynb"))


def test_toc_lists_every_document_and_nothing_else():
    listed, present = toc_files(), book_documents()
    assert not listed - present, f"_toc.yml lists missing documents: {sorted(listed - present)}"
    assert not present - listed, f"documents missing from _toc.yml: {sorted(present - listed)}"


def test_toc_lists_each_document_once():
    entries = toc_entries()
    assert len(entries) == len(set(entries)), "a document is listed twice in _toc.yml"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_is_stored_without_outputs(path):
    nb = json.loads(path.read_text())
    for index, cell in enumerate(nb["cells"]):
        if cell["cell_type"] != "code":
            continue
        assert not cell.get("outputs"), f"{path.name}: cell {index} carries outputs"
        assert cell.get("execution_count") is None, (
            f"{path.name}: cell {index} carries an execution count")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_uses_the_python3_kernel(path):
    nb = json.loads(path.read_text())
    assert nb["metadata"].get("kernelspec", {}).get("name") == "python3", path.name


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_is_small(path):
    assert path.stat().st_size < 200_000, f"{path.name} is {path.stat().st_size} bytes"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_installs_nothing_and_reaches_no_network(path):
    source = "\n".join("".join(c["source"]) for c in json.loads(path.read_text())["cells"])
    assert not re.search(r"^\s*[!%]\s*pip\b", source, re.M), f"{path.name} installs packages"
    assert "urllib.request" not in source and "requests.get" not in source, path.name


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_chapter_has_a_check_and_exercises(path):
    if not re.match(r"\d\d-", path.name):
        pytest.skip("not a numbered chapter")
    cells = json.loads(path.read_text())["cells"]
    code = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
    text = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "markdown")
    assert re.search(r"^\s*assert\b", code, re.M), f"{path.name} has no check cell"
    assert text.count("{exercise") >= 3, f"{path.name} has fewer than three exercises"
    assert "check_function(" in code, f"{path.name} has no automatically checked exercise"


def test_no_unfinished_text_in_the_book():
    pattern = re.compile(r"\b(TODO|FIXME|TBD|lorem ipsum|coming soon|to be written)\b", re.I)
    for path in sorted(BOOK.rglob("*")):
        if path.suffix in {".md", ".ipynb"}:
            hits = pattern.findall(path.read_text())
            assert not hits, f"{path.relative_to(ROOT)} contains {hits}"
