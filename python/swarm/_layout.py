"""NumPy dtypes of the Sense frame's records, built from the Rust layout
(``swarm._native.SENSE_LAYOUT``: ``offset_of!`` / ``size_of`` of the ``#[repr(C)]`` structs),
so the arrays of :class:`swarm.Sense` are views of the frame's own bytes."""

import numpy as np

from . import _native

_L = _native.SENSE_LAYOUT

frombuffer = np.frombuffer
FLOAT64 = np.dtype(np.float64)


def _record(fields, formats, size):
    names = [name for name, _ in fields]
    offsets = [offset for _, offset in fields]
    return np.dtype({"names": names, "formats": [formats[n] for n in names],
                     "offsets": offsets, "itemsize": size})


NEARBY = _record(_L["nearby_fields"], {"robot": np.uint32, "pos": (np.float64, 2),
                                       "vel": (np.float64, 2)}, _L["nearby_size"])
ENTITY = _record(_L["entity_fields"], {"id": np.uint32, "kind": np.uint32, "flags": np.uint32,
                                       "pos": (np.float64, 2), "value": np.float64},
                 _L["entity_size"])
