"""Message values as the ADS publishes them → a frames column, the one their log would give.

A log stores each message as JSON: numbers as they are (float64 round-trips exactly), every
NaN or ±inf as null, numpy arrays as lists. `live_column` builds the Arrow column of the same
values taken before JSON (`evoeye.log.episode_log`) by those rules, whole columns at a time:
a non-finite number becomes null, then numbers take the column's type as Arrow casts a decoded
one. A value it has no columnar rule for (a float32 array, whose JSON is its float32 digits; a
list of numbers) takes the log's own way: JSON-encoded and decoded, then
`pa.array` — so the column equals the log's in every case, only slower in the unusual ones.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import orjson
import pyarrow as pa

from evoeye.log.writer import dumps

_SCALARS = (bool, int, float, str, np.bool_, np.integer, np.float64)  # JSON keeps their values


def as_decoded(value: Any) -> Any:
    """`value` as JSON decoding of its log gives it back (the slow, exact way)."""
    return orjson.loads(dumps(value))


def live_column(values: Sequence[Any], typ: pa.DataType) -> pa.Array:
    """The frames column of type `typ` holding `values` (one per frame, as published)."""
    if pa.types.is_list(typ):
        column = _number_lists(values, typ)
        if column is not None:
            return column
    elif all(v is None or isinstance(v, _SCALARS) for v in values):
        return pa.array([None if isinstance(v, float) and not math.isfinite(v) else v
                         for v in values], typ)
    return pa.array([_as_logged(v) for v in values], typ)


def _as_logged(value: Any) -> Any:
    """`value` as JSON decoding of its log gives it: itself where JSON keeps it (a string, an
    integer, a finite float, a list of strings), None for a non-finite float, else decoded."""
    if value is None or isinstance(value, _SCALARS):
        return None if isinstance(value, float) and not math.isfinite(value) else value
    if type(value) is list and all(type(v) is str for v in value):
        return value
    return as_decoded(value)


def _leaf(typ: pa.DataType) -> tuple[pa.DataType, int]:
    """(the number type inside a list type, its list depth)."""
    depth = 0
    while pa.types.is_list(typ):
        typ, depth = typ.value_type, depth + 1
    return typ, depth


def _number_lists(values: Sequence[Any], typ: pa.DataType) -> pa.Array | None:
    """A list (of lists) of numbers from numpy arrays of that depth, or None when a value is
    not such an array (other dtypes, lists) or the items are not numbers."""
    leaf, depth = _leaf(typ)
    kind = "f" if pa.types.is_floating(leaf) else "i" if pa.types.is_integer(leaf) else None
    if kind is None:
        return None
    dtypes = {np.dtype(np.float64)} if kind == "f" else {np.dtype(np.int64), np.dtype(np.int32)}
    if not all(type(v) is np.ndarray and v.ndim == depth and v.dtype in dtypes for v in values):
        return None
    flat = np.concatenate(values, axis=None) if values else np.zeros(0, next(iter(dtypes)))
    if kind == "f":
        mask = ~np.isfinite(flat)
        with np.errstate(over="ignore"):  # beyond float32: ±inf, as Arrow casts a float
            numbers = flat.astype(leaf.to_pandas_dtype())
        child = pa.array(numbers, leaf, mask=mask if mask.any() else None)
    else:
        child = pa.array(flat.astype(leaf.to_pandas_dtype()), leaf)
    rows = np.array([len(v) for v in values], np.int64)
    lengths = [rows]
    if depth == 2:  # each frame's rows, each row of its frame's width
        lengths.append(np.repeat(np.array([v.shape[1] for v in values], np.int64), rows))
    for count, list_type in zip(reversed(lengths), _list_types(typ)[::-1], strict=True):
        offsets = np.zeros(len(count) + 1, np.int32)
        np.cumsum(count, out=offsets[1:])
        child = pa.ListArray.from_arrays(pa.array(offsets), child, type=list_type)
    return child


def _list_types(typ: pa.DataType) -> list[pa.DataType]:
    """The list types of `typ`, outermost first."""
    out = []
    while pa.types.is_list(typ):
        out.append(typ)
        typ = typ.value_type
    return out
