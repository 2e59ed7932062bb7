"""The rare-failure protocol's tests share synthetic regimes (`rare_curves`)."""

from __future__ import annotations

import pytest
from rare_curves import two_regimes as build_two_regimes


@pytest.fixture(scope="session")
def two_regimes() -> dict:
    """The rare regime (ce-is) and the common one (Sobol) as one protocol run."""
    return build_two_regimes()
