"""The README's practitioner example runs as written and prints what the README shows."""

import contextlib
import io
import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def fenced_block(text, marker, language):
    """The fenced block of ``language`` that follows the HTML comment ``marker``."""
    match = re.search(rf"<!-- {marker} -->\n```{language}\n(.*?)```", text, re.S)
    assert match, f"README.md has no ```{language} block after <!-- {marker} -->"
    return match.group(1)


def test_readme_practitioner_example_runs_and_prints_what_it_shows():
    pytest.importorskip("mujoco")          # the example ends with a MuJoCo run
    text = README.read_text(encoding="utf-8")
    code = fenced_block(text, "practitioner-example", "python")
    shown = fenced_block(text, "practitioner-output", "text")
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exec(compile(code, str(README), "exec"), {"__name__": "readme_example"})
    assert printed.getvalue() == shown


def test_readme_names_exist():
    """Every ``dqlab.`` name the README's prose and code mention is importable."""
    import importlib

    text = README.read_text(encoding="utf-8")
    names = set(re.findall(r"\bdqlab(?:\.\w+)+", text))
    assert "dqlab.quaternion.quaternion_from_xyzw" in names
    for name in sorted(names):
        parts = name.split(".")
        for cut in range(len(parts), 0, -1):     # the longest importable module prefix
            try:
                obj = importlib.import_module(".".join(parts[:cut]))
                break
            except ImportError:
                continue
        for attribute in parts[cut:]:
            obj = getattr(obj, attribute)        # AttributeError: a name that rotted
