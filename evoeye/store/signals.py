"""Where the feature code reads a frame's runtime signals: an Arrow table or live messages.

`evoeye.store.features` computes the monitor inputs from `Signals` — the runtime columns of N
frames by `frames` column name — so one feature code serves ingest (`ArrowSignals` over a frames
table, any N) and the monitor at run time (`evoeye.store.records.MessageSignals`, one frame's
messages, no Arrow on the way).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc


class Signals(Protocol):
    """The runtime signals of N frames, by `frames` column name (schemas/warehouse/frames.sql).

    One feature code serves every source: an Arrow frames table at ingest (`ArrowSignals`), one
    frame's live messages at run time (`evoeye.store.records.MessageSignals`)."""

    def __len__(self) -> int: ...

    def scalar(self, name: str) -> np.ndarray:
        """(N,) float64 of a scalar column."""
        ...

    def items(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(offsets (N+1,) int64 from 0, values float64) of a list column."""
        ...

    def columns(self, names: tuple[str, ...]) -> tuple[np.ndarray, list[np.ndarray]]:
        """`items` of list columns of equal lengths (one message's fields): (offsets, values
        of each)."""
        ...

    def points(self, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(offsets (N+1,) from 0 over the items, offsets (M+1,) over the values — absolute,
        values float64) of a list-of-lists column."""
        ...

    def codes(self, name: str, vocabulary: tuple[str, ...]) -> np.ndarray:
        """(N,) int64 position of a string column's value in `vocabulary`, -1 if absent."""
        ...


class ArrowSignals:
    """The signals of the rows of an Arrow table with `frames` columns (any row count)."""

    def __init__(self, table: pa.Table | pa.RecordBatch):
        self.table = table

    def __len__(self) -> int:
        return len(self.table)

    def _list(self, name: str) -> tuple[np.ndarray, pa.Array]:
        """(offsets (N+1,) int64 from 0, child values) of a list column."""
        arr = self.table.column(name)
        if isinstance(arr, pa.ChunkedArray):
            arr = arr.combine_chunks()
        offsets = arr.offsets.to_numpy().astype(np.int64)
        values = arr.values.slice(offsets[0], offsets[-1] - offsets[0])
        return offsets - offsets[0], values

    def scalar(self, name: str) -> np.ndarray:
        return self.table.column(name).to_numpy(zero_copy_only=False).astype(np.float64)

    def items(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        offsets, values = self._list(name)
        return offsets, values.to_numpy(zero_copy_only=False).astype(np.float64)

    def columns(self, names: tuple[str, ...]) -> tuple[np.ndarray, list[np.ndarray]]:
        offsets, first = self.items(names[0])
        return offsets, [first, *(self.items(name)[1] for name in names[1:])]

    def points(self, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        outer, inner = self._list(name)
        values = inner.values.to_numpy(zero_copy_only=False).astype(np.float64)
        return outer, inner.offsets.to_numpy().astype(np.int64), values

    def codes(self, name: str, vocabulary: tuple[str, ...]) -> np.ndarray:
        code = pc.index_in(self.table.column(name), value_set=pa.array(vocabulary))
        return pc.fill_null(code, -1).to_numpy(zero_copy_only=False).astype(np.int64)
