"""Which runs' modules may share one array program: a key per module object.

Runs are batched together where their modules compute alike (the same configuration, map,
derived constants, bit for bit). A module's key is computed once, from the objects it depends
on, and reused while the module still holds those very objects (checked by identity on every
call, which is cheap). It is kept on the module object itself, with the objects it was made
from (so the ids a key may contain stay theirs): it goes when the module goes, with no weak
reference whose callback a stopping signal could interrupt mid-way (a worker stopped by
SIGTERM raises where it is).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np


class GroupKeys:
    """The group key of each module object of one kind (`name`: the stage's)."""

    def __init__(self, name: str) -> None:
        self._attr = f"_lockstep_key_{name}"

    def get(self, owner: Any, made: tuple, key: Callable[[], tuple]) -> tuple:
        """`owner`'s key: `key()`, computed when `owner` first comes or holds other objects
        `made` of than it did then."""
        hit = owner.__dict__.get(self._attr)
        if hit is not None and all(a is b for a, b in zip(hit[0], made, strict=True)):
            return hit[1]
        computed = key()
        owner.__dict__[self._attr] = (made, computed)
        return computed


def bits(a: np.ndarray | None) -> tuple | None:
    """An array as a hashable, exact value (dtype, shape, bytes); None stays None."""
    return None if a is None else (a.dtype.str, a.shape, a.tobytes())
