"""Former public names: each warned with a DeprecationWarning that named its new home, for
one version; then it is gone, with the error any missing name gives. The book, the tests,
the benchmarks and the tools use the new names."""

import importlib
import re
import sys
import warnings
from pathlib import Path

import pytest

import dqlab.identify
import dqlab.ik.ur_closed_form
import dqlab.testing

ROOT = Path(__file__).resolve().parents[1]

#: The names renamed in 0.1.5 and removed in 0.1.7, and those renamed in 0.1.6 and removed in
#: 0.1.8: modules, and (module, attribute) pairs.
REMOVED_MODULES = ["dqlab.scale", "dqlab.lab_arm"]
REMOVED_ATTRIBUTES = [(dqlab.testing, "check_function"), (dqlab.identify, "calibrate"),
                      (dqlab.ik.ur_closed_form, "ur"),
                      (dqlab.ik.ur_closed_form, "closest_ur_solution"),
                      (dqlab.ik.ur_closed_form, "ur_branch")]
#: The former names as they would be written in code or prose.
FORMER = re.compile(r"dqlab\.scale\b|from dqlab import [^\n]*\bscale\b|\blab_arm\b|"
                    r"uarm_swift_pro|UARM_SWIFT_PRO|\bcalibrate\(|testing import check_function|"
                    r"testing\.check_function|"
                    r"ur_closed_form(\.| import [^\n]*\b)(ur|closest_ur_solution|ur_branch)\b")


def test_the_removed_names_are_gone_with_the_ordinary_errors(monkeypatch):
    # Only dqlab's own folder answers for its submodules (an editable install of another
    # copy of dqlab adds a finder that would look in that copy's folder too).
    monkeypatch.setattr(sys, "meta_path", [f for f in sys.meta_path
                                           if not f.__module__.startswith("__editable")])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for old in REMOVED_MODULES:
            assert not (ROOT / (old.replace(".", "/") + ".py")).exists()
            assert old not in sys.modules
            with pytest.raises(ModuleNotFoundError, match=rf"^No module named '{old}'$") as exc:
                importlib.import_module(old)
            assert exc.value.name == old
            with pytest.raises(ImportError, match=rf"^cannot import name "
                                                  rf"'{old.rpartition('.')[2]}' from 'dqlab'"):
                exec(f"from dqlab import {old.rpartition('.')[2]}", {})
        for module, old in REMOVED_ATTRIBUTES:
            assert not hasattr(module, "__getattr__")
            with pytest.raises(AttributeError, match=rf"^module '{module.__name__}' has no "
                                                     rf"attribute '{old}'$"):
                getattr(module, old)
            with pytest.raises(ImportError, match=rf"^cannot import name '{old}' from "
                                                  rf"'{module.__name__}'"):
                exec(f"from {module.__name__} import {old}", {})
    assert caught == []


def test_the_book_tests_benchmarks_and_tools_use_the_new_names():
    files = [p for pattern in ("book/*.ipynb", "book/**/*.md", "README.md", "tests/*.py",
                               "benchmarks/*.py", "tools/**/*.py")
             for p in ROOT.glob(pattern)
             if p.name not in ("changelog.md", Path(__file__).name)]
    assert len(files) > 50
    found = [f"{p.relative_to(ROOT)}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0)}"
             for p in files for text in [p.read_text(encoding="utf-8")]
             for m in FORMER.finditer(text)]
    assert found == []
