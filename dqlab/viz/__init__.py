"""Pictures of frames, vectors and arms: matplotlib figures and interactive meshcat scenes.

Two families of helpers, both fed by plain dqlab arrays (``(4, 4)`` transforms, ``(..., 3)``
points, FK frames ``(n + 1, 4, 4)``):

* :mod:`dqlab.viz.plots` draws with matplotlib: frames as RGB axes, vectors, a planar arm,
  a serial arm as a 3D stick figure, points in the complex plane. Static figures for the book.
* :mod:`dqlab.viz.scene` builds 3D scenes a reader can turn with the mouse: a robot drawn
  from primitives sized by its DH values, frames, points, paths and animated joint
  trajectories. ``scene.show()`` puts a self-contained view in the notebook output (it
  survives into the built book: no server, no network); ``scene.live()`` mirrors the scene
  to a meshcat server on 127.0.0.1 for teaching.

Examples
--------
>>> import numpy as np
>>> from dqlab import viz
>>> scene = viz.Scene()
>>> scene.add_frame(np.eye(4), name="world")
>>> "world" in scene.html(bundle="none")
True
"""

import importlib.util
import sys

#: True in a browser kernel (Pyodide, e.g. JupyterLite): no processes, no sockets, no zmq.
#: The static views and the figures work there; the live server (tornado, pyzmq) does not.
IN_BROWSER = sys.platform == "emscripten"

_needed = ("matplotlib", "meshcat", "umsgpack") + (() if IN_BROWSER else ("tornado", "zmq"))
_missing = [name for name in _needed if importlib.util.find_spec(name) is None]
if _missing:
    raise ImportError("dqlab.viz needs the viz extra: pip install 'dqlab[viz]' "
                      f"(missing: {', '.join(_missing)})")
if IN_BROWSER:
    from ._browser import import_meshcat

    import_meshcat()  # meshcat's drawing modules without its server (no pyzmq, no tornado)

from .pick_place import animate_pick_place  # noqa: E402, F401
from .plots import (  # noqa: E402
    axes_3d,
    plot_arm,
    plot_complex,
    plot_frame,
    plot_frames,
    plot_planar_arm,
    plot_vector,
    set_axes_equal,
)
from .scene import Scene, SceneView, live_server, stop_live_server  # noqa: E402

__all__ = [
    "Scene", "SceneView", "live_server", "stop_live_server",
    "axes_3d", "set_axes_equal", "plot_frame", "plot_frames", "plot_vector",
    "plot_planar_arm", "plot_arm", "plot_complex",
]
