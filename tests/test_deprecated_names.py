"""Former public names: each warns with a DeprecationWarning that names its new home and is
the new object itself; the book, the tests, the benchmarks and the tools use the new names."""

import importlib
import re
import sys
from pathlib import Path

import pytest

import dqlab.dask_arrays
import dqlab.desk_arm_firmware
import dqlab.exercises
import dqlab.identify

ROOT = Path(__file__).resolve().parents[1]

#: (module, former name, new dotted name) of renamed functions.
RENAMED = [("dqlab.testing", "check_function", "dqlab.exercises.check_function"),
           ("dqlab.identify", "calibrate", "dqlab.identify.identify_dh_parameters"),
           ("dqlab.ik.ur_closed_form", "ur", "dqlab.ik.ur_solver.ur"),
           ("dqlab.ik.ur_closed_form", "closest_ur_solution",
            "dqlab.ik.ur_solver.closest_ur_solution"),
           ("dqlab.ik.ur_closed_form", "ur_branch", "dqlab.ik.ur_solver.ur_branch")]
#: Renamed modules: former name -> (new module, {former attribute: new attribute}).
MODULES = {
    "dqlab.scale": (dqlab.dask_arrays, {n: n for n in dqlab.dask_arrays.__all__}),
    "dqlab.lab_arm": (dqlab.desk_arm_firmware, {
        **{n: n for n in dqlab.desk_arm_firmware.__all__ if n not in ("model", "LENGTHS")},
        "uarm_swift_pro": "model", "UARM_SWIFT_PRO": "LENGTHS"}),
}
#: The former names as they would be written in code or prose.
FORMER = re.compile(r"dqlab\.scale\b|from dqlab import [^\n]*\bscale\b|\blab_arm\b|"
                    r"uarm_swift_pro|UARM_SWIFT_PRO|\bcalibrate\(|testing import check_function|"
                    r"testing\.check_function|"
                    r"ur_closed_form(\.| import [^\n]*\b)(ur|closest_ur_solution|ur_branch)\b")


def _new(dotted):
    module, _, name = dotted.rpartition(".")
    return getattr(importlib.import_module(module), name)


def test_each_former_name_warns_where_it_is_used_and_is_the_new_object(monkeypatch):
    for module, old, new in RENAMED:
        with pytest.warns(DeprecationWarning, match=rf"^{module}\.{old} is deprecated: use "
                                                    rf"{re.escape(new)}\b") as caught:
            assert getattr(importlib.import_module(module), old) is _new(new)
        assert caught[0].filename == __file__                  # the line that used the name
    with pytest.warns(DeprecationWarning, match=r"^dqlab\.testing\.check_function is deprec"):
        from dqlab.testing import check_function
    assert check_function is dqlab.exercises.check_function
    with pytest.raises(AttributeError, match="has no attribute 'calibration'"):
        dqlab.identify.calibration                              # noqa: B018
    for old, (new, names) in MODULES.items():
        monkeypatch.delitem(sys.modules, old, raising=False)   # imported afresh, so it warns
        monkeypatch.delattr(dqlab, old.rpartition(".")[2], raising=False)
        with pytest.warns(DeprecationWarning, match=rf"^{old} is deprecated: use "
                                                    rf"{new.__name__}\b") as caught:
            module = importlib.import_module(old)
        assert set(module.__all__) == set(names)
        assert all(getattr(module, a) is getattr(new, b) for a, b in names.items())
    monkeypatch.delitem(sys.modules, "dqlab.scale")
    monkeypatch.delattr(dqlab, "scale")
    with pytest.warns(DeprecationWarning) as caught:
        from dqlab import scale
    assert caught[0].filename == __file__ and scale.fk_dask is dqlab.dask_arrays.fk_dask


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
