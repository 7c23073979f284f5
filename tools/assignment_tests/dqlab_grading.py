"""What the tests of the assignment set use when they grade a notebook (shipped in every bundle).

The tests of an exercise (``tests/<label>.py`` in a bundle, written by ``tools/assignments.py``)
run in the global namespace of the executed submission. Three kinds:

* the exercise's **automatic check**, the student edition's check cell without its guard
  (:func:`run_check`);
* **hidden tests** written in ``tools/assignment_tests/chNN.py``, functions whose parameters
  are the student's names (:func:`hidden` marks them, :func:`run_hidden` calls them);
* inside a hidden test, :func:`own_work` runs the student's function and fails if it calls
  what the exercise asks the student to write (dqlab's solver, the chapter's reference), and
  :func:`agrees` compares a function with a reference on random inputs.

Every failure is an ``AssertionError`` whose message starts with the exercise's label, so that
the feedback says which exercise lost the points.
"""

import contextlib
import importlib
import inspect
import io
import signal
import sys
import types

import numpy as np

#: Longest a single test may run, in seconds (a student's endless loop must not stop grading).
TIME_LIMIT = 120

#: Longest message quoted from a failure, in characters (its first line only).
MESSAGE_LENGTH = 240


def hidden(label, points=1):
    """Mark a function as a hidden test of exercise ``label`` worth ``points``.

    Its first docstring line is what the feedback calls it; its parameters are the names of
    the student's answer (functions or values) that it tests.
    """
    def mark(test):
        test.hidden_test = {"label": label, "points": points}
        return test
    return mark


def _shorten(text):
    text = " ".join(str(text).strip().split("\n")[0].split())
    return text if len(text) <= MESSAGE_LENGTH else text[:MESSAGE_LENGTH - 3] + "..."


@contextlib.contextmanager
def _time_limit(seconds):
    """Raise TimeoutError after ``seconds`` (where the platform has SIGALRM, in the main thread)."""
    usable, previous = hasattr(signal, "SIGALRM"), None
    try:
        previous = signal.signal(signal.SIGALRM, _timeout) if usable else None
    except ValueError:          # not the main thread
        usable = False
    if usable:
        signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        if usable:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, signal.SIG_DFL if previous is None else previous)


def _timeout(signum, frame):
    raise TimeoutError(f"stopped after {TIME_LIMIT} s")


def run_check(env, label, waiting, code):
    """Run an exercise's automatic check in the submission's namespace ``env``.

    Fails, naming the exercise, if one of the ``waiting`` names is not defined or if the check
    fails (quoting the line of the check that failed).
    """
    missing = [name for name in waiting if name not in env]
    if missing:
        raise AssertionError(f"{label}: not answered (define {', '.join(missing)})")
    filename = f"<automatic check of {label}>"
    lines = code.split("\n")
    try:
        with _time_limit(TIME_LIMIT), contextlib.redirect_stdout(io.StringIO()):
            exec(compile(code, filename, "exec"), env)
    except Exception as error:
        line = None
        tb = error.__traceback__
        while tb is not None:
            if tb.tb_frame.f_code.co_filename == filename:
                line = lines[tb.tb_lineno - 1].strip()
            tb = tb.tb_next
        where = f" at `{_shorten(line)}`" if line else ""
        detail = _shorten(f"{type(error).__name__}: {error}") if str(error) else type(
            error).__name__
        raise AssertionError(f"{label}: the automatic check fails{where}: {detail}") from None


def run_hidden(env, label, test):
    """Call the hidden test ``test`` with the student's names it asks for, taken from ``env``."""
    names = list(inspect.signature(test).parameters)
    missing = [name for name in names if name not in env]
    if missing:
        raise AssertionError(f"{label}: not answered (define {', '.join(missing)})")
    what = (test.__doc__ or test.__name__).strip().split("\n")[0]
    try:
        with _time_limit(TIME_LIMIT), contextlib.redirect_stdout(io.StringIO()):
            test(*(env[name] for name in names))
    except AssertionError as error:
        raise AssertionError(_shorten(f"{label}: {what}: no. {error}")) from None
    except Exception as error:
        raise AssertionError(_shorten(
            f"{label}: {what}: no, it raised {type(error).__name__}: {error}")) from None


def _resolve(spec):
    """The object named by a dotted path such as ``"dqlab.sclerp"`` or ``"numpy.linalg.solve"``."""
    parts = spec.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for part in parts[k:]:
            obj = getattr(obj, part)
        return obj
    raise ValueError(f"forbid: cannot import {spec!r}")


def _codes_of(obj):
    """The code objects of a function, a method or every method of a class."""
    if isinstance(obj, type):
        return {code for value in vars(obj).values() for code in _codes_of(value)}
    obj = getattr(obj, "__func__", obj)                  # a bound method
    obj = getattr(obj, "fget", obj)                      # a property
    obj = getattr(obj, "_implementation", obj)           # numpy's array-function dispatchers
    obj = inspect.unwrap(obj) if callable(obj) else obj
    code = getattr(obj, "__code__", None)
    return {code} if code is not None else set()


class _Matcher:
    """Which calls a specification names: modules, dotted names, functions, classes."""

    def __init__(self, specs):
        self.modules, self.codes, self.objects = [], {}, []
        for spec in specs:
            obj = _resolve(spec) if isinstance(spec, str) else spec
            name = spec if isinstance(spec, str) else getattr(obj, "__qualname__", repr(obj))
            if isinstance(obj, types.ModuleType):
                self.modules.append(obj.__name__)
                continue
            codes = _codes_of(obj)
            self.codes.update(dict.fromkeys(codes, name))
            if not codes:
                self.objects.append((obj, name))

    def name(self, frame, event, arg):
        """The name of what is called (for a "call" or "c_call" event), or None."""
        if event == "call":
            if frame.f_code in self.codes:
                return self.codes[frame.f_code]
            module = frame.f_globals.get("__name__", "") or ""
            for prefix in self.modules:
                if module == prefix or module.startswith(prefix + "."):
                    return f"{module}.{frame.f_code.co_name}"
        elif event == "c_call":
            for obj, name in self.objects:
                if arg is obj:
                    return name
        return None


def own_work(function, *args, forbid=("dqlab",), require=()):
    """``function(*args)``, failing if it calls anything in ``forbid`` or nothing of ``require``.

    ``forbid`` and ``require`` hold modules (every function defined in them, e.g. ``"dqlab"``),
    dotted names of functions (``"dqlab.sclerp"``, ``"numpy.linalg.solve"``), functions
    themselves (a reference defined in the chapter) or classes (any of their methods). The
    calls are recorded with :func:`sys.setprofile`, so an alias, a wrapper or a lambda around
    a forbidden function is caught as well. ``require`` checks an intermediate step: that the
    function computes its answer the way the exercise asks (from the Jacobian, on dual
    numbers...), each entry being called at least once.
    """
    forbidden, required = _Matcher(forbid), [(_Matcher([spec]), spec) for spec in require]
    called, seen = [], set()

    def profile(frame, event, arg):
        name = forbidden.name(frame, event, arg)
        if name is not None:
            called.append(name)
        for k, (matcher, _) in enumerate(required):
            if k not in seen and matcher.name(frame, event, arg) is not None:
                seen.add(k)

    previous = sys.getprofile()
    sys.setprofile(profile)
    try:
        result = function(*args)
    finally:
        sys.setprofile(previous)
    if called:                                  # the first is the one the function called
        raise AssertionError(f"it calls {called[0]}; the exercise asks for your own code")
    missing = [spec if isinstance(spec, str) else getattr(spec, "__qualname__", repr(spec))
               for k, (_, spec) in enumerate(required) if k not in seen]
    if missing:
        raise AssertionError(f"it never calls {', '.join(missing)}, which the exercise asks "
                             "it to use")
    return result


def agrees(function, reference, sample, *, n=50, seed=0, atol=1e-9, forbid=(), require=()):
    """Compare ``function`` with ``reference`` on ``n`` inputs drawn by ``sample(rng)``.

    With ``forbid`` or ``require``, each call of ``function`` also goes through
    :func:`own_work`. Fails with the first input where the two differ by more than ``atol``
    (or have other shapes).
    """
    rng = np.random.default_rng(seed)
    for _ in range(n):
        args = sample(rng)
        got = (own_work(function, *args, forbid=forbid, require=require)
               if forbid or require else function(*args))
        want = reference(*args)
        got, want = np.asarray(got, dtype=float), np.asarray(want, dtype=float)
        assert got.shape == want.shape, (
            f"shape {got.shape} instead of {want.shape} for input {_shorten(repr(args))}")
        assert np.allclose(got, want, rtol=0, atol=atol), (
            f"off by {np.max(np.abs(got - want)):.3g} for input {_shorten(repr(args))}")
