"""Deprecated: the former name of :mod:`dqlab.dask_arrays` (dqlab's batch functions on dask
arrays, chunk by chunk). Importing it warns with a :class:`DeprecationWarning`; its names are
those of :mod:`dqlab.dask_arrays`."""

from ._deprecated import warn_renamed
from .dask_arrays import (  # noqa: F401
    INSTALL,
    IKArrays,
    dexterity_dask,
    fk_dask,
    ik_ur_dask,
    reachability_map,
)

__all__ = ["fk_dask", "ik_ur_dask", "IKArrays", "dexterity_dask", "reachability_map"]

warn_renamed("dqlab.scale", "dqlab.dask_arrays")
