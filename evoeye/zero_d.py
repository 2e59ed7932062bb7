"""Constants as 0-d float64 arrays, for the per-frame array arithmetic on a handful of actors.

numpy combines an array with a Python float (or a numpy scalar) through NEP 50's weak-scalar
promotion, ≈ 0.2 µs per operation on this machine (numpy 2.4), and with a 0-d float64 array
without it: `a * 2.0` costs 0.52 µs on 7 elements, `a * zero_d(2.0)` 0.31 µs. The result is
the same bits (the same float64 loop runs), so the per-frame modules keep their configuration
and per-frame scalars in this form where they meet arrays. A 0-d array combined with another
0-d array or a Python float gives a numpy scalar, which is slow again: precompute such
sub-expressions once, as `zero_d` of the Python value.
"""

from __future__ import annotations

from dataclasses import fields
from types import SimpleNamespace

import numpy as np


def zero_d(value: float) -> np.ndarray:
    """`value` as a read-only 0-d float64 array."""
    a = np.array(value, dtype=np.float64)
    a.flags.writeable = False
    return a


def zero_d_fields(config) -> SimpleNamespace:
    """A dataclass's float fields as 0-d arrays (`zero_d`), by the same names."""
    return SimpleNamespace(**{f.name: zero_d(v) for f in fields(config)
                              if type(v := getattr(config, f.name)) is float})
