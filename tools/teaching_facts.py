"""Sphinx extension: facts of the teaching guide computed from the chapters at build time.

``{{ exercise_checks }}`` becomes the table of :func:`editions.check_table`: per part and per
chapter, the number of exercises and of those that check themselves in the student edition.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import editions  # noqa: E402


def _set_facts(app, config):
    substitutions = dict(getattr(config, "myst_substitutions", None) or {})
    substitutions["exercise_checks"] = editions.check_table()
    config.myst_substitutions = substitutions


def setup(app):
    app.connect("config-inited", _set_facts)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
