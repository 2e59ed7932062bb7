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


def test_an_inner_block_freezes_nothing_more_and_only_the_outermost_thaws() -> None:
    # Counts alone cannot show this: frozen objects that reference counting frees (another
    # thread's, say) leave the permanent generation, so the count may only fall in the block.
    assert gc.get_freeze_count() == 0
    gc.disable()  # no collection but the test's own
    try:
        older = cycle()
        with frozen_heap():
            assert gc.get_freeze_count() > 1000  # the interpreter's and the test run's objects
            between = cycle()
            with frozen_heap():
                gc.collect()
                assert between() is None  # made after the outermost block froze: not frozen again
            gc.collect()
            assert older() is not None  # the inner block's end thawed nothing
        assert gc.get_freeze_count() == 0
        gc.collect()
        assert older() is None
    finally:
        gc.enable()


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
