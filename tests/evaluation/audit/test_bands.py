"""Every simulated logical scenario is judged against a collision-rate band."""

import pytest

from evoeye.evaluation.audit import COLLISION_BANDS
from evoeye.scenarios import SCENARIOS


@pytest.mark.parametrize("scenario", sorted(SCENARIOS))
def test_every_scenario_has_a_collision_band(scenario):
    lo, hi = COLLISION_BANDS[scenario]
    assert 0.0 < lo < hi < 1.0
