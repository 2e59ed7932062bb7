"""0-d constants: the same bits as the Python float they stand for, in every operation used."""

from __future__ import annotations

import operator
from dataclasses import dataclass

import numpy as np
import pytest

from evoeye.zero_d import zero_d, zero_d_fields


@pytest.mark.parametrize("op", [operator.add, operator.sub, operator.mul, operator.truediv,
                                operator.lt, operator.le, np.maximum, np.minimum])
def test_an_array_combined_with_a_0d_constant_gives_the_bits_of_the_python_float(op) -> None:
    rng = np.random.default_rng(0)
    value = float(rng.normal())
    for a in (rng.normal(size=9) * 1e3, rng.normal(size=9) + 1j * rng.normal(size=9),
              rng.integers(-5, 5, size=9), rng.random(9) < 0.5):
        if a.dtype.kind == "c" and op in (operator.lt, operator.le, np.maximum, np.minimum):
            continue
        for left, right in ((a, value), (value, a)):
            with np.errstate(divide="ignore", invalid="ignore"):  # x / False
                want = op(left, right)
                got = op(zero_d(left) if left is value else left,
                         zero_d(right) if right is value else right)
            assert got.dtype == want.dtype
            assert got.tobytes() == want.tobytes()


def test_a_constant_is_read_only_and_a_config_gives_its_float_fields() -> None:
    @dataclass(frozen=True)
    class Config:
        rate_hz: float = 20.0
        count: int = 3
        name: str = "x"

    k = zero_d_fields(Config())
    assert k.rate_hz.shape == () and float(k.rate_hz) == 20.0
    assert not hasattr(k, "count") and not hasattr(k, "name")
    with pytest.raises(ValueError):
        k.rate_hz[...] = 1.0
    assert zero_d(2.5).dtype == np.float64
