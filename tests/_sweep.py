"""The bad-input sweeps' one machinery: bad values of every kind, one case run and judged, counts.

A sweep registers :class:`Case` objects: a callable that takes keyword arguments, the good
value and the kind of each argument (:class:`Arg`), and optionally a check of what it
returns. :func:`run` replaces each argument, one at a time, by every bad value of its kind
and judges the outcome:

* **clear error**: ``ValueError`` or ``TypeError`` whose message names the argument (by its
  name or one of the names given), or for a magnitude says the result overflows, is too large
  or is out of reach; for a path or a file, an ``OSError`` or a ``ValueError`` naming the
  file. The message must fit a few lines (:data:`MAX_MESSAGE`): it may quote a line of the
  bad value, never all of it. A writer's old file must be left as it was.
* **correct**: the call returns, its numbers are finite, the case's check (if any) accepts the
  result, and the bad value was one the argument may take: an empty batch gives an empty
  result, a magnitude a finite one, None where None means "the default", infinity where it
  switches a check off, any shape where the argument takes any, a numpy scalar anywhere a
  number goes.
* **other**: anything else -- a crash, an error naming something else, a silent wrong answer,
  a message quoting a whole value, a call that does not finish within :data:`TIME_LIMIT`.

Each case's good call runs first (outside the time limit): it must work, and it warms what
the bad calls share (compiled kernels, caches).

Each sweep test records its counts on its report (``user_properties``), and the test
session's summary (``tests/conftest.py``) adds them up per sweep and module: no test depends on
another, on their order or on running in one process.
"""

import os
import re
import signal
import warnings
from collections import Counter
from dataclasses import dataclass, field, fields, is_dataclass
from pathlib import Path

import numpy as np

#: The longest message an error may carry, characters, and its most lines.
MAX_MESSAGE, MAX_LINES = 600, 4
#: Seconds one call may take before it counts as a hang (generous: a bad value may make a
#: compiled kernel compile for a new shape of input, on a loaded machine).
TIME_LIMIT = 30

ARRAY_KINDS = ("nan", "inf", "none", "text", "complex", "wrong_shape", "ragged", "empty",
               "huge", "tiny", "far", "farthest")
#: More kinds for an argument whose good value is one number.
NUMBER_KINDS = ("bool", "numeric_text", "numpy")
INT_KINDS = ARRAY_KINDS + NUMBER_KINDS + ("fraction", "big_int", "negative_big_int")
OBJECT_KINDS = ("none", "number", "text", "list", "bool")
FLAG_KINDS = ("none", "number", "text", "list")
TEXT_KINDS = ("none", "number", "list", "control", "newline", "surrogate", "long")
PATH_KINDS = ("none", "number", "list", "directory", "missing_folder")
FILE_KINDS = ("none", "number", "list", "directory", "missing", "empty", "binary",
              "truncated", "huge_file", "nested", "long_line")

#: The kinds that are magnitudes: a finite result, or an error saying the numbers are too
#: large (or small), is the right answer.
MAGNITUDES = ("huge", "tiny", "far", "farthest", "big_int", "negative_big_int")
_MAGNITUDE_WORDS = re.compile(r"overflow|too large|too big|too small|too far|out of reach|"
                              r"unreachable|beyond", re.I)


@dataclass
class Arg:
    """An argument: its good value and kind -- "array" (a fixed shape), "any" (an array of
    any shape), "scalar", "int", "object" (a robot, a choice among names...), "text" (free
    text: any one line is valid), "name" (text written into a file: refused unless one
    line of printable text), "path" (a file to write), "file" (a file to read: its good
    value is the file's name in the case's folder); ``none_ok``: None is valid (the
    default); ``inf_ok``: infinity is (a tolerance or a limit that it switches off);
    ``names``: other names the messages may use for it."""

    value: object
    kind: str = "array"
    none_ok: bool = False
    inf_ok: bool = False
    names: tuple = ()
    extra: dict = None
    only: tuple = None

    def kinds(self):
        """The kinds of bad values of this argument: those of its kind (or ``only`` these),
        then its ``extra`` ones (a name -> a bad value, or a function of the case's folder
        that makes one: a degenerate robot, a corrupt file of a given format...)."""
        if self.only is not None:
            kinds = self.only
        elif self.kind in ("array", "any"):
            kinds = ARRAY_KINDS
        elif self.kind == "scalar":
            kinds = ARRAY_KINDS + NUMBER_KINDS
        else:
            kinds = {"int": INT_KINDS, "object": OBJECT_KINDS, "flag": FLAG_KINDS,
                     "text": TEXT_KINDS, "name": TEXT_KINDS, "path": PATH_KINDS,
                     "file": FILE_KINDS}[self.kind]
        return tuple(kinds) + tuple(self.extra or ())


@dataclass
class Fine:
    """An ``extra`` value that is unusual but valid: a finite result that passes the case's
    check is the right answer (a link of 1e300 kg, a robot without link inertias)."""

    value: object


def Flag(value):
    return Arg(value, "flag")


def A(value, none_ok=False, names=(), extra=None, inf_ok=False):
    return Arg(value, "array", none_ok, inf_ok, names, extra)


def Any(value):
    return Arg(value, "any")


def S(value, none_ok=False, inf_ok=False, names=(), extra=None):
    return Arg(value, "scalar", none_ok, inf_ok, names, extra)


def Int(value, none_ok=False, names=(), extra=None):
    return Arg(value, "int", none_ok, names=names, extra=extra)


def O(value, none_ok=False, names=(), extra=None):  # noqa: E743
    return Arg(value, "object", none_ok, names=names, extra=extra)


def T(value, none_ok=False, only=None):
    return Arg(value, "text", none_ok, only=only)


def Name(value, none_ok=False):
    return Arg(value, "name", none_ok)


def P(value):
    return Arg(value, "path")


def F(value, extra=None):
    return Arg(value, "file", extra=extra)


@dataclass
class Case:
    """One public callable of a sweep: ``call(**kwargs)`` with ``args`` (name -> Arg);
    ``check(result, kwargs)`` is True when a returned result is right (beyond finite);
    ``writes``: the name of the argument that is the file it writes (its old content must
    survive an error)."""

    module: str
    title: str
    call: object
    args: dict
    check: object = None
    writes: str = None
    setup: object = field(default=None, repr=False)


class Registry(dict):
    """The cases of one sweep, by title, and their groups: the cases one test runs (by
    default a case is its own group; a sweep of one argument per case groups a callable's)."""

    def __init__(self):
        super().__init__()
        self.groups = {}

    def add(self, module, title, call, *, check=None, writes=None, group=None, **args):
        assert title not in self, title
        self[title] = Case(module, title, call, args, check, writes)
        self.groups.setdefault(group or title, []).append(self[title])
        return self[title]


_FOLDER = []


def warm_ik_batches(robot):
    """A case's setup (run before its calls, outside the time limit) for ``dqlab.ik.ur`` on a
    calibrated ``robot``: a good call of one pose compiles the one-pose path only, and a bad
    value of one (a tolerance too tight for any branch, say) takes the array paths, whose
    first compilation on a fresh cache takes longer than :data:`TIME_LIMIT`. A batch of
    three poses and one of twelve compile them (the paths of at most eight poses and of
    more)."""
    from dqlab import ik

    def setup(folder):
        q = np.random.default_rng(0).uniform(-np.pi, np.pi, (12, 6))
        ik.ur(robot, robot.fk(q[:3]))
        ik.ur(robot, robot.fk(q))
    return setup


def folder():
    """The folder of the case being run (its working directory)."""
    return _FOLDER[-1]


# -- bad values ----------------------------------------------------------------------------

def bad_value(value, kind):
    """``value`` turned into a bad value of ``kind`` (numbers and arrays)."""
    if kind == "none":
        return None
    if kind == "text":
        return "abc"
    if kind == "ragged":
        return [[1.0, 2.0], [3.0]]
    if kind == "bool":
        return True
    if kind == "numeric_text":
        return str(value)
    if kind == "numpy":
        return np.int64(value) if isinstance(value, (int, np.integer)) else np.float64(value)
    if kind == "fraction":
        return value + 0.5
    if kind == "big_int":
        return 10 ** 30
    if kind == "negative_big_int":
        return -10 ** 30
    a = np.asarray(value, dtype=float)
    first = np.arange(a.size).reshape(a.shape) == 0
    if kind == "nan":
        return np.where(first, np.nan, a)
    if kind == "inf":
        return np.where(first, np.inf, a)
    if kind == "complex":
        return a + 1j
    if kind == "wrong_shape":
        return a[..., :-1] if a.ndim else np.ones((2, 3, 5))
    if kind == "empty":
        return np.zeros((0,) + a.shape)
    if kind == "huge":
        return a * 1e200
    if kind == "tiny":
        return a * 1e-200
    if kind in ("far", "farthest"):
        far = 1e100 if kind == "far" else -1e300
        if a.shape[-2:] == (4, 4):                     # a transform: its position
            out = a.copy()
            out[..., 0, 3] = far
            return out
        return np.where(first, far, a)
    raise AssertionError(kind)


def bad_object(kind, folder):
    """A bad value of an object, a text or a path argument."""
    return {"none": None, "number": 123, "text": "abc", "list": [1.0, 2.0], "bool": True,
            "directory": folder, "missing_folder": folder / "no such folder" / "file.out",
            "control": "x\x00y", "newline": "x\nM2231 V1", "surrogate": "x\ud800",
            "long": ("line of a long text " * 8 + "\n") * 2000}[kind]


def bad_file(kind, good, folder):
    """A file to read, bad in the way ``kind`` says, made from the good file ``good``."""
    path = folder / f"bad-{kind}{good.suffix}"
    if kind == "missing":
        return folder / f"no such file{good.suffix}"
    data = good.read_bytes()
    if kind == "empty":
        data = b""
    elif kind == "binary":
        data = bytes(range(256)) * 64
    elif kind == "truncated":
        data = data[:len(data) // 2]
    elif kind == "nested":
        data = b"[" * 200_000 + b"]" * 200_000
    elif kind == "long_line":
        data = data[:64] + b"1" * 8_000_000 + b"\n"
    if kind == "huge_file":              # a sparse file of 300 MB: no reader should read it
        with open(path, "wb") as f:
            f.truncate(300 << 20)
        return path
    path.write_bytes(data)
    return path


# -- judging a result ----------------------------------------------------------------------

def numbers_finite(result):
    """Every number ``result`` holds (arrays, tuples, dicts, dataclasses) is finite."""
    if result is None or isinstance(result, (str, bytes, bool, np.bool_, type, Path)):
        return True
    if isinstance(result, (int, float, np.number, np.ndarray)):
        a = np.asarray(result)
        return a.dtype.kind not in "fc" or bool(np.isfinite(a).all())
    if isinstance(result, dict):
        return all(numbers_finite(v) for v in result.values())
    if isinstance(result, (tuple, list)):
        return all(numbers_finite(v) for v in result)
    if type(result).__name__ == "ReachabilityMap":    # its median is NaN where nothing reaches
        return all(numbers_finite(getattr(result, k)) for k in
                   ("positions", "orientations", "reachable", "branches"))
    if hasattr(result, "solutions") and hasattr(result, "valid"):    # an IK result
        valid = np.asarray(result.valid)
        return all(numbers_finite(np.asarray(getattr(result, name))[valid]) for name in
                   ("solutions", "position_error", "rotation_error") if hasattr(result, name))
    if is_dataclass(result):
        if type(result).__name__ in _INF_IS_NO_LIMIT:
            return not any(np.isnan(np.asarray(getattr(result, f.name), dtype=float)).any()
                           for f in fields(result)
                           if f.name != "robot" and getattr(result, f.name) is not None)
        return all(numbers_finite(getattr(result, f.name)) for f in fields(result)
                   if f.name not in ("robot", "law", "condition_number"))
    return True


#: Results whose infinite numbers mean "no limit" (only NaN is wrong in them).
_INF_IS_NO_LIMIT = ("SafetyLimits",)


def is_empty(result):
    """``result`` holds an empty batch: an array of size 0 in it."""
    if isinstance(result, np.ndarray):
        return result.size == 0
    if isinstance(result, dict):
        return any(is_empty(v) for v in result.values())
    if isinstance(result, (tuple, list)):
        return any(is_empty(v) for v in result)
    if hasattr(result, "solutions"):
        return np.size(result.solutions) == 0
    if is_dataclass(result):
        return any(is_empty(getattr(result, f.name)) for f in fields(result))
    return False


def names_the_argument(message, names):
    """``message`` names one of ``names`` as a word (``q`` in "q must ...", not in "qd")."""
    return any(re.search(rf"(?<![\w]){re.escape(n)}(?![\w])", message) for n in names)


def message_problem(message):
    """Why an error message is too long to be read (None when it is not)."""
    if len(message) > MAX_MESSAGE:
        return f"a message of {len(message)} characters (at most {MAX_MESSAGE})"
    if message.count("\n") >= MAX_LINES:
        return f"a message of {message.count(chr(10)) + 1} lines (at most {MAX_LINES})"
    return None


class _Hang(BaseException):
    """Raised by the alarm: a call took longer than TIME_LIMIT (not an Exception, so that no
    ``except Exception`` of the code under test swallows it)."""


def _on_alarm(signum, frame):
    raise _Hang()


def _call_with_time_limit(call, kwargs):
    """``call(**kwargs)`` within TIME_LIMIT, a RuntimeWarning (an overflow, a NaN made, a
    complex number cast) raised as the error it is, whatever the session's filters."""
    previous = signal.signal(signal.SIGALRM, _on_alarm)
    signal.setitimer(signal.ITIMER_REAL, TIME_LIMIT)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            return call(**kwargs)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


OLD_CONTENT = b"the file that was there before: a failed write must leave it\n"


def judge(case, label, kind, kwargs, folder):
    """Run ``case`` with ``kwargs`` (``label`` bad, of ``kind``) and judge: ("clear error" |
    "correct" | "other", why)."""
    arg = case.args[label]
    target = None
    if case.writes:
        target = kwargs[case.writes]
        if isinstance(target, (str, Path)) and not Path(folder, target).is_dir():
            target = Path(folder, target)
            if target.parent.is_dir():
                target.write_bytes(OLD_CONTENT)
            else:
                target = None
        else:
            target = None
    names = (label,) + tuple(arg.names)
    try:
        result = _call_with_time_limit(case.call, kwargs)
    except _Hang:
        return "other", f"no answer within {TIME_LIMIT} s"
    except TimeoutError as exc:          # a tiny timeout honoured, or a huge stream stopped
        if kind in MAGNITUDES:
            return "correct", ""
        return "other", f"TimeoutError: {str(exc)[:200]}"
    except (ValueError, TypeError, OSError) as exc:
        message = str(exc)
        if kind == "numpy":
            return "other", f"a numpy number refused: {type(exc).__name__}: {message[:200]}"
        if target is not None and label != case.writes and target.exists() \
                and target.read_bytes() != OLD_CONTENT:
            return "other", f"the failed write changed {target.name}: {message[:200]}"
        problem = message_problem(message)
        if problem:
            return "other", f"{type(exc).__name__}: {problem}: {message[:200]}..."
        named = (names_the_argument(message, names)
                 and not (isinstance(exc, OSError) and not isinstance(exc, ValueError)))
        if kind in MAGNITUDES and _MAGNITUDE_WORDS.search(message):
            named = True
        if arg.kind in ("path", "file"):
            bad = kwargs[label]
            named = named or (isinstance(bad, (str, Path)) and str(Path(bad).name) in message)
        if named:
            return "clear error", ""
        return "other", f"{type(exc).__name__} does not name {names}: {message[:300]}"
    except Exception as exc:                                        # a crash
        return "other", f"crash: {type(exc).__name__}: {str(exc)[:300]}"
    finite = numbers_finite(result)
    allowed = ((kind == "empty" and is_empty(result))
               or (arg.extra and isinstance(arg.extra.get(kind), Fine))
               or kind in MAGNITUDES
               or kind == "numpy"
               or (arg.kind == "any" and kind in ("wrong_shape", "empty"))
               or (kind == "none" and arg.none_ok)
               or (kind == "inf" and arg.inf_ok)
               or (arg.kind == "text" and kind in TEXT_KINDS and kind not in ("none",
                                                                              "number",
                                                                              "list")))
    if not allowed:
        return "other", f"accepted: {short(result)}"
    if not finite:
        return "other", f"accepted, with a number that is not finite: {short(result)}"
    if case.check is not None and not (kind == "empty" and is_empty(result)):
        try:
            verdict = case.check(result, kwargs)
        except Exception as exc:
            verdict = f"the check failed: {type(exc).__name__}: {str(exc)[:200]}"
        if verdict is not True:
            return "other", f"accepted, wrong: {verdict}"
    return "correct", ""


def short(value, limit=300):
    text = repr(value)
    return text if len(text) <= limit else text[:limit] + "..."


def good_kwargs(case):
    return {k: a.value for k, a in case.args.items()}


def run(case, folder):
    """Every bad value of every argument of ``case``, in ``folder`` (the working directory
    meanwhile): (counts, failures), the failures as readable lines."""
    counts, failures = Counter(), []
    folder = Path(folder)
    here = os.getcwd()
    os.chdir(folder)
    _FOLDER.append(folder)
    try:
        if case.setup:
            case.setup(folder)
        good = case.call(**good_kwargs(case))    # first: it warms caches and compiled kernels
        verdict = case.check(good, good_kwargs(case)) if case.check else True
        if not numbers_finite(good) or verdict is not True:
            failures.append(f"{case.title}: the good call's result is wrong: {verdict}")
        for label, arg in case.args.items():
            for kind in arg.kinds():
                kwargs = good_kwargs(case)
                if arg.extra and kind in arg.extra:
                    bad = arg.extra[kind]
                    bad = bad.value if isinstance(bad, Fine) else bad
                    kwargs[label] = bad(folder) if callable(bad) else bad
                elif arg.kind in ("object", "text", "name", "path", "flag") or (
                        kind in OBJECT_KINDS + ("directory",) and arg.kind == "file"):
                    kwargs[label] = bad_object(kind, folder)
                elif arg.kind == "file":
                    kwargs[label] = bad_file(kind, folder / arg.value, folder)
                else:
                    kwargs[label] = bad_value(arg.value, kind)
                outcome, why = judge(case, label, kind, kwargs, folder)
                counts[outcome] += 1
                if outcome == "other":
                    failures.append(f"{case.title}: {label} = {kind}: {' '.join(why.split())}")
    finally:
        _FOLDER.pop()
        os.chdir(here)
    return counts, failures


def record(request, sweep, module, counts):
    """Put the counts on the test's report, for the session's summary."""
    request.node.user_properties.append(("sweep", (sweep, module, dict(counts))))


def sweep_test(request, cases, folder, sweep):
    """The body of a sweep test: run ``cases`` (one case or a group), record their counts,
    fail on any "other", listing them."""
    total, failures = Counter(), []
    for case in cases if isinstance(cases, list) else [cases]:
        counts, failed = run(case, folder)
        record(request, sweep, case.module, counts)
        total.update(counts)
        failures += failed
    assert not failures, f"{len(failures)} of {sum(total.values())} cases:\n" + "\n".join(
        failures)


def summary_lines(reports):
    """The table of the sweeps' counts, from the test reports of a session."""
    totals = {}
    for report in reports:
        for key, value in getattr(report, "user_properties", ()):
            if key != "sweep":
                continue
            sweep, module, counts = value
            totals.setdefault(sweep, {}).setdefault(module, Counter()).update(counts)
    if not totals:
        return []
    lines = [f"{'sweep':24s} {'module':22s} {'cases':>6s} {'clear error':>12s} "
             f"{'correct':>8s} {'other':>6s}"]
    for sweep in sorted(totals):
        modules = totals[sweep]
        for module in sorted(modules) + ["total"]:
            c = (sum(modules.values(), Counter()) if module == "total" else modules[module])
            lines.append(f"{sweep:24s} {module:22s} {sum(c.values()):6d} "
                         f"{c['clear error']:12d} {c['correct']:8d} {c['other']:6d}")
    return lines


# -- checks of what a call returns ---------------------------------------------------------

#: How far a solution marked valid may put the tool from its target: metres, and the largest
#: entry of the rotation's difference (absolute: a target 1e100 m away is not "reached" to
#: a relative 1e-9).
REACH_TOL = 1e-6


def _as_transforms(target):
    from dqlab import transform_from_dual_quaternion

    t = np.asarray(target, dtype=float)
    return transform_from_dual_quaternion(t) if t.shape[-1] == 8 else t


def _pose_gap(robot, q, X):
    """The largest position and rotation gaps between ``robot.fk(q)`` and ``X``."""
    reached = robot.fk(q)
    return (float(np.max(np.abs(reached[..., :3, 3] - X[..., :3, 3]), initial=0.0)),
            float(np.max(np.abs(reached[..., :3, :3] - X[..., :3, :3]), initial=0.0)))


def _tolerance(kwargs):
    """How far a valid row may be: REACH_TOL, or more when the call was given a looser
    ``tol`` (``inf``: any row the solver returns is valid)."""
    tol = kwargs.get("tol")
    try:
        return max(REACH_TOL, 10 * float(tol))
    except (TypeError, ValueError):
        return REACH_TOL


def _robot_of(robot, kwargs):
    """The robot a call solved for: ``robot`` (else the call's), with the call's tool."""
    robot = kwargs.get("robot") if robot is None else robot
    tool = kwargs.get("tool")
    return robot if tool is None else robot.with_tool(tool)


def reaches_target(robot=None, target="target", position_only=False):
    """A check: every row an IK result marks valid puts the tool on the target (``robot``
    None: the call's own robot; a ``tool`` argument of the call is applied)."""
    def check(result, kwargs):
        solved = _robot_of(robot, kwargs)
        X = _as_transforms(kwargs[target]) if not position_only else np.asarray(
            kwargs[target], dtype=float)
        valid = np.asarray(result.valid)
        if not valid.any():
            return True
        q = np.asarray(result.solutions)[valid]
        lead = valid.shape[:-1]
        if position_only:
            goal = np.broadcast_to(X[..., None, :], lead + valid.shape[-1:] + (3,))[valid]
            gap = float(np.max(np.abs(solved.fk(q)[..., :3, 3] - goal)))
            if gap <= _tolerance(kwargs):
                return True
            return f"a valid row is {gap:.3g} m off its target"
        goal = np.broadcast_to(X[..., None, :, :], lead + valid.shape[-1:] + (4, 4))[valid]
        gap, turn = _pose_gap(solved, q, goal)
        if gap <= _tolerance(kwargs) and turn <= _tolerance(kwargs):
            return True
        return f"a valid row is {gap:.3g} m and {turn:.3g} (rotation) off its target"
    return check


def joints_reach_target(robot=None, target="target", limits=None):
    """A check: joints returned for a target put the tool there, within the limits."""
    def check(q, kwargs):
        solved = _robot_of(robot, kwargs)
        X = _as_transforms(kwargs[target])
        gap, turn = _pose_gap(solved, q, X)
        if not (gap <= _tolerance(kwargs) and turn <= _tolerance(kwargs)):
            return f"the joints are {gap:.3g} m and {turn:.3g} (rotation) off the target"
        lims = np.asarray(solved.limits if limits is None or kwargs.get(limits) is None
                          else kwargs[limits], dtype=float)
        if np.any(q < lims[..., 0] - 1e-12) or np.any(q > lims[..., 1] + 1e-12):
            return f"joints {np.round(q, 3).tolist()} outside the limits"
        return True
    return check
