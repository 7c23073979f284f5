"""dqlab.viz in a browser kernel (Pyodide, as in JupyterLite): meshcat without its server.

meshcat's package imports its live server on import (``meshcat.visualizer`` imports pyzmq and
``meshcat.servers.zmqserver``, which imports tornado). A browser kernel has neither and cannot
start processes or open sockets, but it does not need them: :class:`dqlab.viz.Scene` records
meshcat's drawing commands and replays them in a self-contained view. :func:`import_meshcat`
imports meshcat with two stand-ins for exactly those two modules, present only while meshcat
is imported, so that the drawing classes (``meshcat.Visualizer`` on a recording window,
``meshcat.geometry``, ``meshcat.animation``) work and anything that would reach a server
raises :class:`LiveServerUnavailable` with the reason.
"""

import contextlib
import importlib.util
import sys
import types

#: What a browser kernel says when asked for the live server.
LIVE_SERVER_MESSAGE = ("the live meshcat server needs Python on a computer (it runs as a "
                       "separate process with network sockets); in the browser, "
                       "scene.show() draws the scene in the notebook instead")


class LiveServerUnavailable(RuntimeError):
    """The live meshcat server was asked for in a browser kernel."""

    def __init__(self, *args):
        super().__init__(LIVE_SERVER_MESSAGE)


def _unavailable(*args, **kwargs):
    raise LiveServerUnavailable()


def _importable(name):
    """Whether ``name`` can be imported (False for a stand-in without a spec: Pyodide's
    kernel puts a bare ``tornado`` module in ``sys.modules`` for other packages' sake)."""
    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):
        return False


def _stand_ins():
    """Stand-ins for ``zmq`` and ``meshcat.servers.zmqserver``, for those that cannot import.

    With pyzmq and tornado installed (a computer) the result is empty: meshcat imports as is.
    """
    absent = {name for name in ("zmq", "tornado.web") if not _importable(name)}
    if not absent:
        return {}
    zmq = types.ModuleType("zmq", "Stand-in for pyzmq while meshcat is imported in a browser.")
    zmq.REQ = 3                                     # pyzmq's value; read, never used

    class Context:
        socket = staticmethod(_unavailable)

    zmq.Context = Context
    server = types.ModuleType("meshcat.servers.zmqserver",
                              "Stand-in for meshcat's server in a browser kernel.")
    server.start_zmq_server_as_subprocess = _unavailable
    stand_ins = {"meshcat.servers.zmqserver": server}
    if "zmq" in absent:
        stand_ins["zmq"] = zmq
    return stand_ins


@contextlib.contextmanager
def _modules(stand_ins):
    """Put ``stand_ins`` in ``sys.modules`` for the block; take them out afterwards."""
    taken = {name: sys.modules[name] for name in stand_ins if name in sys.modules}
    sys.modules.update(stand_ins)
    try:
        yield
    finally:
        for name, module in stand_ins.items():
            if sys.modules.get(name) is module:
                del sys.modules[name]
        sys.modules.update(taken)


def import_meshcat():
    """Import meshcat for drawing only, in a kernel without pyzmq and tornado.

    Returns
    -------
    module
        The ``meshcat`` package, fully imported. Where pyzmq or tornado is missing, the
        stand-ins are no longer in ``sys.modules`` after the call: only meshcat's own modules
        keep them, and they raise :class:`LiveServerUnavailable` when used.

    Examples
    --------
    >>> meshcat = import_meshcat()
    >>> meshcat.Visualizer.__name__
    'Visualizer'
    """
    if "meshcat" in sys.modules:
        return sys.modules["meshcat"]
    with _modules(_stand_ins()):
        import meshcat
        import meshcat.visualizer  # noqa: F401
    return meshcat
