"""Former public names, kept for one version after a rename.

Each warns with a :class:`DeprecationWarning` that names its new home, then gives the new
object itself: a renamed function or constant is served by the module's ``__getattr__``
(:pep:`562`) and warns each time it is looked up.
"""

import importlib
import warnings


def warn_renamed(old, new):
    """Warn that ``old`` is deprecated in favour of ``new``.

    The warning points at the code that used the old name: the caller of the function
    that calls this one (a module's ``__getattr__``).
    """
    warnings.warn(f"{old} is deprecated: use {new} (the old name goes in the next version)",
                  DeprecationWarning, stacklevel=3)


def renamed_attributes(module, renamed):
    """A module ``__getattr__`` that serves the former names of ``module``.

    Parameters
    ----------
    module : str
        The module's name (``__name__``), quoted in the warning and in the error for a name
        it does not have.
    renamed : dict of str to str
        Each former name and the dotted path of its new object
        (``{"ur": "dqlab.ik.ur_solver.ur"}``).

    Returns
    -------
    callable
        ``__getattr__(name)``: the new object for a former name, after a
        :class:`DeprecationWarning`; ``AttributeError`` for any other name.
    """
    def __getattr__(name):
        try:
            new = renamed[name]
        except KeyError:
            raise AttributeError(f"module {module!r} has no attribute {name!r}") from None
        warn_renamed(f"{module}.{name}", new)
        home, _, attribute = new.rpartition(".")
        return getattr(importlib.import_module(home), attribute)

    return __getattr__
