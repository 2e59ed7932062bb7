"""Which runs' modules may share one array program: a key per module object.

Runs are batched together where their modules compute alike (the same configuration, map,
derived constants, bit for bit). A module's key is computed once, from the objects it depends
on, and reused while the module still holds those very objects (checked by identity on every
call, which is cheap); the cache holds the objects, so the ids a key may contain stay theirs.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from typing import Any

import numpy as np


class GroupKeys:
    """The group key of each module object (weakly held: a module that is gone leaves)."""

    def __init__(self) -> None:
        self._keys: weakref.WeakKeyDictionary[Any, tuple[tuple, tuple]] = (
            weakref.WeakKeyDictionary())

    def get(self, owner: Any, made: tuple, key: Callable[[], tuple]) -> tuple:
        """`owner`'s key: `key()`, computed when `owner` first comes or holds other objects
        `made` of than it did then."""
        hit = self._keys.get(owner)
        if hit is not None and all(a is b for a, b in zip(hit[0], made, strict=True)):
            return hit[1]
        computed = key()
        self._keys[owner] = (made, computed)
        return computed


def bits(a: np.ndarray | None) -> tuple | None:
    """An array as a hashable, exact value (dtype, shape, bytes); None stays None."""
    return None if a is None else (a.dtype.str, a.shape, a.tobytes())
