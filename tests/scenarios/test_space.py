"""Logical scenario spaces: declaration, validation, sampling, distance, neighbourhoods."""

import numpy as np
import pytest

from evoeye.scenarios import SCENARIOS, ScenarioError, get_scenario

HIGHWAY = get_scenario("highway-cut-in")
CROSSING = get_scenario("unprotected-intersection")


def test_declared_sizes_match_the_paper():
    assert HIGHWAY.dim == 20
    assert CROSSING.dim == 10
    assert all(p.unit and p.meaning for s in SCENARIOS.values() for p in s.parameters)


def test_unknown_scenario_names_the_known_ones():
    with pytest.raises(ScenarioError, match="highway-cut-in"):
        get_scenario("roundabout")


@pytest.mark.parametrize("space", list(SCENARIOS.values()), ids=list(SCENARIOS))
def test_uniform_samples_are_in_range_and_seeded(space):
    a = space.sample(np.random.default_rng(3), 500)
    b = space.sample(np.random.default_rng(3), 500)
    np.testing.assert_array_equal(a, b)
    assert a.shape == (500, space.dim)
    assert (a >= space.low).all() and (a <= space.high).all()
    # uniform on each axis: every decile of every parameter is hit
    u = space.normalise(a)
    for j in range(space.dim):
        assert len(np.unique(np.floor(u[:, j] * 10))) == 10


def test_out_of_range_value_names_the_parameter():
    x = HIGHWAY.sample(np.random.default_rng(0))
    x[HIGHWAY.index("lead_gap_m")] = 1000.0
    with pytest.raises(ScenarioError, match="lead_gap_m"):
        HIGHWAY.validate(x)


def test_nan_and_wrong_length_are_rejected():
    x = CROSSING.sample(np.random.default_rng(0))
    x[0] = np.nan
    with pytest.raises(ScenarioError, match="opp_left_speed_mps"):
        CROSSING.validate(x)
    with pytest.raises(ScenarioError, match="expected a vector of 10"):
        CROSSING.validate(np.zeros(9))


def test_distance_is_on_normalised_parameters():
    a = CROSSING.low.copy()
    b = a.copy()
    j = CROSSING.index("opp_left_offset_s")
    b[j] += 0.5 * CROSSING.parameters[j].span
    assert CROSSING.distance(a, b) == pytest.approx(0.5)
    assert CROSSING.distance(a, a) == 0.0
    # broadcasting over a batch of candidates
    assert CROSSING.distance(np.stack([a, b]), a).tolist() == pytest.approx([0.0, 0.5])


def test_neighbourhood_samples_stay_within_delta_and_in_range():
    rng = np.random.default_rng(1)
    x = HIGHWAY.low.copy()  # a corner: the box must be clipped to the space
    near = np.stack([HIGHWAY.sample_near(x, rng, delta=0.2) for _ in range(300)])
    assert (HIGHWAY.distance(near, x) <= 0.2 + 1e-12).all()
    assert (near >= HIGHWAY.low).all()
    # and they fill the clipped box, not a point
    assert HIGHWAY.normalise(near).max(axis=0).min() > 0.15


def test_neighbourhood_rejects_bad_delta():
    with pytest.raises(ScenarioError, match="delta"):
        HIGHWAY.sample_near(HIGHWAY.low, np.random.default_rng(0), delta=0.0)


def test_scenario_id_is_stable_and_sensitive():
    x = CROSSING.sample(np.random.default_rng(5))
    assert CROSSING.scenario_id(x, 7) == CROSSING.scenario_id(x.copy(), 7)
    assert CROSSING.scenario_id(x, 7) != CROSSING.scenario_id(x, 8)
    y = x.copy()
    y[0] = np.nextafter(y[0], np.inf) if y[0] < CROSSING.high[0] else y[0] - 1e-6
    assert CROSSING.scenario_id(x, 7) != CROSSING.scenario_id(y, 7)
    assert CROSSING.scenario_id(x, 7).startswith("unprotected-intersection-")


def test_dict_round_trip_and_missing_keys():
    x = HIGHWAY.sample(np.random.default_rng(2))
    np.testing.assert_array_equal(HIGHWAY.from_dict(HIGHWAY.as_dict(x)), x)
    d = HIGHWAY.as_dict(x)
    del d["ego_speed_mps"]
    with pytest.raises(ScenarioError, match="ego_speed_mps"):
        HIGHWAY.from_dict(d)


def test_every_parameter_belongs_to_an_actor_and_npcs_match_the_paper():
    assert set(HIGHWAY.actors) == {"ego", "lead", "left_cutin", "right_cutin", "left_follow",
                                   "right_follow", "overtaker"}  # the ego and six NPCs
    assert len(CROSSING.actors) == 5 and all(len(ix) == 2 for ix in CROSSING.actors.values())
    flat = sorted(i for ix in HIGHWAY.actors.values() for i in ix)
    assert flat == list(range(HIGHWAY.dim))
