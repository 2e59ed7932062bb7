"""frozen_heap: full collections skip the start-up heap inside the block, and only there."""

from __future__ import annotations

import gc
import weakref

from evoeye.heap import frozen_heap


class Node:
    def __init__(self) -> None:
        self.other: Node | None = None


def cycle() -> weakref.ref:
    """A reference cycle nothing else holds; a weak reference to one of its nodes."""
    a, b = Node(), Node()
    a.other, b.other = b, a
    return weakref.ref(a)


def test_the_heap_is_frozen_in_the_block_and_thawed_after_the_outermost() -> None:
    assert gc.get_freeze_count() == 0
    with frozen_heap():
        frozen = gc.get_freeze_count()
        assert frozen > 1000  # the interpreter's and the test run's objects
        with frozen_heap():
            assert gc.get_freeze_count() == frozen  # an inner block freezes nothing more
        assert gc.get_freeze_count() == frozen
    assert gc.get_freeze_count() == 0


def test_cycles_made_in_the_block_are_collected_in_it_and_older_ones_after() -> None:
    gc.disable()  # no collection but the test's own
    try:
        older = cycle()
        with frozen_heap():
            newer = cycle()
            gc.collect()
            assert newer() is None  # made in the block: collected as always
            assert older() is not None  # frozen: left alone
        gc.collect()
        assert older() is None
    finally:
        gc.enable()
