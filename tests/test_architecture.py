"""The package's structure: public names between modules, no import cycle, a numpy-only core,
no function that shadows a module of its package."""

import ast
import importlib
import math
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import dqlab

PACKAGE = Path(dqlab.__file__).resolve().parent
SOURCES = sorted(PACKAGE.rglob("*.py"))


def module_name(path):
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def is_package(path):
    return path.name == "__init__.py"


def imports(path):
    """``(module, names)`` of every import statement in ``path`` (anywhere in the file,
    function-level imports included), with relative imports resolved."""
    tree = ast.parse(path.read_text())
    here = module_name(path)
    package = here if is_package(path) else here.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, ()
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                target = f"{base}.{node.module}" if node.module else base
            else:
                target = node.module
            yield target, tuple(alias.name for alias in node.names)


MODULES = {module_name(p): p for p in SOURCES}


def dqlab_edges(path):
    """The dqlab modules that ``path`` imports (``from pkg import submodule`` counts as an
    import of the submodule)."""
    for target, names in imports(path):
        if target.split(".")[0] != "dqlab":
            continue
        subs = [f"{target}.{n}" for n in names if f"{target}.{n}" in MODULES]
        if subs:
            yield from subs
        else:
            yield target


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_module_imports_another_modules_private_name(path):
    private = [(target, name) for target, names in imports(path) for name in names
               if name.startswith("_") and not name.startswith("__")]
    assert not private, f"{module_name(path)} imports private names {private}"


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_reach_into_another_objects_private_attributes(path):
    """``x._name`` only on ``self`` or ``cls``: objects talk through public methods."""
    tree = ast.parse(path.read_text())
    reach = [f"line {node.lineno}: {ast.unparse(node)}" for node in ast.walk(tree)
             if isinstance(node, ast.Attribute) and node.attr.startswith("_")
             and not node.attr.startswith("__")
             and not (isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"))]
    assert not reach, f"{module_name(path)} reaches into private attributes: {reach}"


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_docstring_holds_a_control_character(path):
    """A backslash of LaTeX in a docstring that is not raw may begin an escape
    (``\\theta`` reads as a tab and 'heta', ``\\beta`` as a backspace and 'eta'): such a
    docstring is raw."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    bad = [getattr(node, "name", "module") for node in ast.walk(tree)
           if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
           and any(c in (ast.get_docstring(node, clean=False) or "") for c in "\t\b\f\a\v")]
    assert not bad, f"{path.name}: a docstring with an escape (make it raw): {bad}"


def test_the_imports_between_dqlab_modules_have_no_cycle():
    graph = {name: set(dqlab_edges(path)) - {name} for name, path in MODULES.items()}
    state = {}

    def visit(node, trail):
        state[node] = "open"
        for child in sorted(graph.get(node, ())):
            if state.get(child) == "open":
                cycle = trail[trail.index(child):] + [child]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if child not in state:
                visit(child, trail + [child])
        state[node] = "done"

    for name in sorted(graph):
        if name not in state:
            visit(name, [name])
    # the walk sees the arrows it should (a smoke test of the test itself)
    assert "dqlab._fast.chain" in graph["dqlab.robot"]
    assert "dqlab.dualquat" in graph["dqlab._fast.chain"]
    assert "dqlab.ik.ur_steps" in graph["dqlab._fast.ur_engine"]


def test_robot_and_jacobian_depend_one_way():
    assert "dqlab.jacobian" not in set(dqlab_edges(MODULES["dqlab.robot"]))


CORE_IMPORT = ("import sys, dqlab, dqlab.models, dqlab.robot, dqlab.ik, dqlab.jacobian; "
               "import numpy as np; robot = dqlab.models.ur3(); "
               "dqlab.ik.ur(robot, robot.fk(np.zeros(6))); "
               "print(sorted(m for m in ('matplotlib', 'meshcat', 'pyquaternion', 'scipy') "
               "if m in sys.modules))")


def test_the_core_imports_numpy_alone():
    out = subprocess.run([sys.executable, "-c", CORE_IMPORT], capture_output=True, text=True,
                         check=True, cwd=PACKAGE.parent)
    assert out.stdout.strip() == "[]", out.stdout + out.stderr


@pytest.mark.parametrize("package", ["dqlab", "dqlab.ik", "dqlab.viz"])
def test_no_attribute_shadows_a_module_of_its_package(package):
    pkg = importlib.import_module(package)
    for info in pkgutil.iter_modules(pkg.__path__):
        importlib.import_module(f"{package}.{info.name}")
        value = getattr(pkg, info.name, None)
        assert value is None or value is sys.modules[f"{package}.{info.name}"], (
            f"{package}.{info.name} is {value!r}, not the module of that name")


def test_the_ik_solvers_are_functions_and_no_module_alias_is_left():
    import dqlab.ik

    assert callable(dqlab.ik.ur) and callable(dqlab.ik.numerical)
    for old in ("dqlab.ik.ur", "dqlab.ik.numerical"):
        assert old not in sys.modules
        with pytest.raises(ModuleNotFoundError):
            importlib.import_module(old)


# The speed twins: machinery that makes a readable path fast, all in one private package,
# dqlab._fast. Each sits behind one front, the only module that imports it, and is registered
# here beside the test that holds it equal to the readable path it speeds up (or, for
# generated code, to its generator's output). One Newton step and one forward kinematics per
# twin: the calibrated solver's numpy kernels (calibrated_matrices, calibrated_entries), its
# compiled ones (newton_compiled, over the generated newton_lanes), the closed form's engine
# (ur_engine), the chain's products (chain), the dynamics on floats and compiled.
ENGINES = {
    "dqlab._fast.chain": ({"dqlab.robot"}, "test_robot.py::"
                          "test_fk_is_the_product_of_link_transforms_with_base_and_tool"),
    # the calibrated solver starts from the closed form of the nearest exact UR: it calls
    # the engine directly, its arguments checked already, instead of dqlab.ik.ur
    "dqlab._fast.ur_engine": ({"dqlab.ik.ur_closed_form", "dqlab.ik.ur_calibrated"},
                              "test_ik_ur.py::test_single_pose_path_equals_the_batch_path"),
    "dqlab._fast.calibrated_matrices": (
        {"dqlab.ik.ur_calibrated", "dqlab._fast.calibrated_entries"},
        "test_ik_ur_calibrated.py::test_kernels_equal_forward_kinematics_and_jacobian"),
    "dqlab._fast.calibrated_entries": (
        {"dqlab.ik.ur_calibrated"},
        "test_ik_ur_calibrated.py::test_kernels_equal_forward_kinematics_and_jacobian"),
    "dqlab._fast.newton_compiled": (
        {"dqlab.ik.ur_calibrated"}, "test_ik_ur_calibrated_compiled.py::"
        "test_results_are_the_same_with_and_without_the_compiled_kernels"),
    "dqlab._fast.newton_lanes": ({"dqlab._fast.newton_compiled"},
                                 "test_ik_ur_calibrated_compiled.py::"
                                 "test_the_generated_lanes_are_those_of_the_generator"),
    "dqlab._fast.dynamics_floats": ({"dqlab.dynamics"}, "test_dynamics.py::"
                                    "test_the_float_path_equals_the_readable_path"),
    "dqlab._fast.dynamics_compiled": ({"dqlab.dynamics"}, "test_dynamics_compiled.py::"
                                      "test_the_compiled_kernels_equal_the_numpy_path"),
}
#: the switch of the compiled paths (DQLAB_COMPILED) and their compiler: not a twin
SWITCH = "dqlab._fast.compiled"


@pytest.mark.parametrize("engine", sorted(ENGINES))
def test_each_engine_is_reached_through_its_front_only(engine):
    users = {name for name, path in MODULES.items() if engine in set(dqlab_edges(path))}
    assert users == ENGINES[engine][0]


@pytest.mark.parametrize("engine", sorted(ENGINES))
def test_each_engine_has_its_equality_test(engine):
    file, test = ENGINES[engine][1].split("::")
    source = (Path(__file__).parent / file).read_text(encoding="utf-8")
    assert f"def {test}(" in source, f"{file} has no {test}"


def test_every_speed_twin_is_in_the_private_package_and_registered():
    """Every module of dqlab._fast but the switch is in ENGINES, and no module outside it
    is named like a twin (compiled, float-only, unrolled kernels)."""
    fast = {name for name in MODULES if name.startswith("dqlab._fast.")}
    assert fast - {SWITCH} == set(ENGINES)
    outside = {name for name in MODULES if not name.startswith("dqlab._fast") and re.search(
        r"\._\w*(compiled|floats|engine|lanes|chains?|kernels)$", name)}
    assert outside == set()
    users = {name for name, path in MODULES.items() if SWITCH in set(dqlab_edges(path))}
    assert users <= set(ENGINES) | {SWITCH}


# The readable references: a fast public solver, the public module written to be read that
# a chapter shows in its place, and the test that holds the two equal. A reference reaches
# no speed twin, directly or through the fast solver's private helpers.
REFERENCES = {
    "dqlab.ik.ur_calibrated": ("dqlab.ik.ur_calibrated_reference",
                               "test_ik_ur_calibrated_reference.py::"
                               "test_the_reference_and_the_fast_solver_give_the_same_solutions"),
}


@pytest.mark.parametrize("fast", sorted(REFERENCES))
def test_each_fast_solver_has_a_reference_held_equal_to_it(fast):
    reference, test = REFERENCES[fast]
    file, name = test.split("::")
    source = (Path(__file__).parent / file).read_text(encoding="utf-8")
    assert f"def {name}(" in source, f"{file} has no {name}"
    assert fast in MODULES and not set(dqlab_edges(MODULES[reference])) & set(ENGINES)
    tree = ast.parse(MODULES[reference].read_text())
    private = [node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
               for alias in node.names if alias.name.startswith("_")]
    assert private == [], f"{reference} imports private names from {private}"


def float_switches(path):
    """The places of ``path`` that tell a Python float from an array: ``type(x) is float``
    (or ``is not``) and ``isinstance(x, np.ndarray)``, as (function, line) pairs."""
    tree = ast.parse(path.read_text())
    found = []
    for function in ast.walk(tree):
        if not isinstance(function, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        for node in ast.walk(function):
            if (isinstance(node, ast.Compare) and isinstance(node.ops[0], (ast.Is, ast.IsNot))
                    and isinstance(node.comparators[0], ast.Name)
                    and node.comparators[0].id == "float"):
                found.append((function.name, node.lineno))
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                    and node.func.id == "isinstance" and len(node.args) == 2
                    and ast.unparse(node.args[1]) == "np.ndarray"):
                found.append((function.name, node.lineno))
    return found


CORE = [p for p in SOURCES if (module_name(p) + ".").split(".")[1] in
        ("complex", "rotations", "quaternion", "transforms", "dualquat", "robot", "models",
         "jacobian", "ik", "_formulas", "_checks", "_wrapper")] + [
    MODULES[name] for name in ("dqlab._fast.chain", "dqlab._fast.ur_engine",
                               "dqlab._fast.calibrated_matrices",
                               "dqlab._fast.calibrated_entries", "dqlab._fast.newton_compiled",
                               "dqlab._fast.newton_lanes")]


def test_the_core_tells_floats_from_arrays_in_one_place():
    """One switch between the float path and the array path of a formula: the mapping
    dqlab._formulas.functions_for from the type of a number to its functions. No other
    place of the core tests for a float, except where the test is not a choice of formula:
    wrap_angle and check_scalar, which skip their argument checks for a Python float, and
    the calibrated solver's dot product of entries (dqlab._fast.calibrated_entries.dot),
    which skips the entries that are the float 0.0 (the
    structural zeros of its Jacobian's entries)."""
    from dqlab._formulas import functions_for

    sites = {(module_name(p), name) for p in CORE for name, _ in float_switches(p)}
    assert sites == {("dqlab.rotations", "wrap_angle"), ("dqlab._checks", "check_scalar"),
                     ("dqlab._fast.calibrated_entries", "dot")}
    floats, arrays = functions_for(float), functions_for(np.ndarray)
    assert floats.atan2 is math.atan2 and arrays.atan2 is np.arctan2
    assert functions_for(np.float64) is arrays and functions_for((float, np.ndarray)) is arrays
    assert functions_for((float, float)) is floats
