"""Sphinx extension: the book's version and date, from ``pyproject.toml`` and ``CITATION.cff``.

The version is the package's (``[project] version`` in ``pyproject.toml``, the same string as
``dqlab.__version__``); the date is the release date of that version (``date-released`` in
``CITATION.cff``). Both become MyST substitutions, ``{{ book_version }}`` and
``{{ book_date }}``, and Sphinx's own ``version`` and ``release``. The build stops if the two
files name different versions.
"""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def book_version(root=ROOT):
    """``(version, date)`` of the book; ``ValueError`` if the two sources disagree."""
    project = (Path(root) / "pyproject.toml").read_text(encoding="utf-8")
    match = re.search(r'^version\s*=\s*"([^"]+)"', project, flags=re.M)
    citation = (Path(root) / "CITATION.cff").read_text(encoding="utf-8")
    cited = re.search(r"^version:\s*\"?([^\"\s]+)\"?\s*$", citation, flags=re.M)
    date = re.search(r"^date-released:\s*\"?(\d{4}-\d\d-\d\d)\"?\s*$", citation, flags=re.M)
    if not (match and cited and date):
        raise ValueError("pyproject.toml needs a version, CITATION.cff a version and a "
                         "date-released")
    if match[1] != cited[1]:
        raise ValueError(f"pyproject.toml says version {match[1]}, CITATION.cff {cited[1]}: "
                         f"update CITATION.cff (and the changelog) with the version")
    return match[1], date[1]


def _set_version(app, config):
    version, date = book_version()
    config.version = config.release = version
    substitutions = dict(getattr(config, "myst_substitutions", None) or {})
    substitutions.update(book_version=version, book_date=date)
    config.myst_substitutions = substitutions


def setup(app):
    app.connect("config-inited", _set_version)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
