"""The book as something to cite and to trust: one version everywhere, shown in the book,
with a citation record, a changelog entry and an errata page."""

import re
import sys
from pathlib import Path

import dqlab

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import book_version  # noqa: E402


def test_one_version_in_the_package_the_metadata_and_the_citation():
    version, date = book_version.book_version()
    assert version == dqlab.__version__
    assert re.fullmatch(r"\d{4}-\d\d-\d\d", date)
    citation = (ROOT / "CITATION.cff").read_text(encoding="utf-8")
    for field in ("cff-version:", "title:", "authors:", "license:", "repository-code:"):
        assert field in citation


def test_the_book_shows_its_version_and_lists_its_changes_and_errata():
    version, date = book_version.book_version()
    preface = (ROOT / "book" / "preface.md").read_text(encoding="utf-8")
    assert "{{ book_version }}" in preface and "{{ book_date }}" in preface
    changelog = (ROOT / "book" / "changelog.md").read_text(encoding="utf-8")
    assert re.search(rf"^## {re.escape(version)} \({date}\)$", changelog, re.M), (
        f"the changelog has no section '## {version} ({date})'")
    errata = (ROOT / "book" / "errata.md").read_text(encoding="utf-8")
    assert "| where | what was wrong | what is right |" in errata
    toc = (ROOT / "_toc.yml").read_text(encoding="utf-8")
    for page in ("changelog", "errata", "teaching-guide"):
        assert f"file: book/{page}" in toc


def test_a_disagreeing_citation_stops_the_build(tmp_path):
    (tmp_path / "pyproject.toml").write_text('[project]\nversion = "9.9.9"\n')
    (tmp_path / "CITATION.cff").write_text('version: "0.0.1"\ndate-released: "2026-01-01"\n')
    try:
        book_version.book_version(tmp_path)
    except ValueError as error:
        assert "9.9.9" in str(error) and "0.0.1" in str(error)
    else:
        raise AssertionError("a version mismatch was not refused")
