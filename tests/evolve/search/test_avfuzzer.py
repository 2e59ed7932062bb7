"""AV-Fuzzer as docs/avfuzzer.md specifies it: operators, roulette, restart, local search,
ask/tell, resume."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evoeye.evolve.search import AVFuzzer, StrategyError, criticality
from evoeye.evolve.search.avfuzzer import (
    actor_groups,
    crossover,
    mutate,
    roulette_select,
    roulette_weights,
)
from evoeye.scenarios import SCENARIOS, get_scenario

HIGHWAY = get_scenario("highway-cut-in")  # 7 gene groups incl. the ego's single gene
CROSSING = get_scenario("unprotected-intersection")  # 5 NPCs × 2 genes


def _drive(ga, fitness_of, n):
    """Propose/tell n times; returns [(x, kind, generation, told fitness)]."""
    log = []
    for _ in range(n):
        prop = ga.propose()
        gen = ga.generation
        f = float(fitness_of(prop.x, prop.kind))
        ga.tell(prop.x, f)
        log.append((prop.x, prop.kind, gen, f))
    return log


def _distance_to(space, hidden_u):
    """Synthetic criticality: normalised Euclidean distance to a hidden point, clipped to 1."""

    def fit(x, _kind=None):
        gap = np.linalg.norm(space.normalise(x) - hidden_u) / np.sqrt(space.dim)
        return min(1.0, 2.0 * gap)

    return fit


def test_criticality_is_the_min_gap_over_ten_metres_and_zero_on_collision():
    fit = criticality(
        np.array([False, False, False, True, False]), np.array([5.0, 25.0, 0.0, 3.0, np.nan])
    )
    np.testing.assert_allclose(fit, [0.5, 1.0, 0.0, 0.0, 1.0])  # NaN: a failed run, not critical
    assert float(criticality(False, None)) == 1.0


@pytest.mark.parametrize("space", [HIGHWAY, CROSSING], ids=["highway", "crossing"])
def test_crossover_swaps_exactly_one_actor_between_two_parents(space):
    groups = actor_groups(space)
    chosen = set()
    for seed in range(200):
        rng = np.random.default_rng(seed)
        parents = space.sample(rng, 2)
        children = crossover(parents, groups, rng, p=1.0)
        differs = np.flatnonzero(np.any(children != parents, axis=0))
        hits = [a for a, ix in space.actors.items() if set(differs) == set(ix)]
        assert len(hits) == 1  # exactly one whole actor's genes moved
        ix = list(space.actors[hits[0]])
        np.testing.assert_array_equal(children[0, ix], parents[1, ix])
        np.testing.assert_array_equal(children[1, ix], parents[0, ix])
        chosen.add(hits[0])
    assert chosen == set(space.actors)  # every actor, the ego included, can be swapped
    rng = np.random.default_rng(0)
    pop = space.sample(rng, 4)
    np.testing.assert_array_equal(crossover(pop, groups, rng, p=0.0), pop)


def test_mutation_redraws_exactly_one_gene_of_one_actor_within_its_range():
    groups = actor_groups(HIGHWAY)
    rng = np.random.default_rng(0)
    ego_hits = 0
    for _ in range(2100):
        x = HIGHWAY.sample(rng, 1)
        y = mutate(x, groups, HIGHWAY.low, HIGHWAY.high, rng, p=1.0)
        changed = np.flatnonzero(y[0] != x[0])
        assert len(changed) == 1
        k = changed[0]
        assert HIGHWAY.low[k] <= y[0, k] <= HIGHWAY.high[k]
        ego_hits += k == HIGHWAY.index("ego_speed_mps")
    # the actor is drawn first (1 of 7), then its gene: the ego's only gene gets 1/7, not 1/20
    assert abs(ego_hits / 2100 - 1 / 7) < 0.03


def test_excluded_actors_are_never_touched():
    groups = actor_groups(HIGHWAY, exclude=("ego",))
    rng = np.random.default_rng(1)
    pop = HIGHWAY.sample(rng, 4)
    for _ in range(200):
        new = mutate(crossover(pop, groups, rng, 1.0), groups, HIGHWAY.low, HIGHWAY.high, rng, 1.0)
        np.testing.assert_array_equal(new[:, 0], pop[:, 0])
    with pytest.raises(ValueError, match="unknown actors"):
        actor_groups(HIGHWAY, exclude=("pedestrian",))


def test_roulette_weights_favour_critical_runs_with_a_floor():
    w = roulette_weights(np.array([0.0, 0.5, 1.0, 1.2]))
    np.testing.assert_allclose(w, np.array([1.0, 0.5, 0.001, 0.001]) / 1.502)
    picks = roulette_select(np.array([0.0, 0.5, 1.0]), np.random.default_rng(0), 30000)
    np.testing.assert_allclose(np.bincount(picks) / 30000, [1 / 1.501, 0.5 / 1.501, 0], atol=0.01)


def test_restart_after_five_stagnant_generations_keeps_the_best():
    ga = AVFuzzer(CROSSING, seed=3)
    first = ga.propose()
    ga.tell(first.x, 0.1)  # the very first run stays the best forever
    log = _drive(ga, lambda x, kind: 0.5, 150)
    restarts = [gen for _, kind, gen, _ in log if kind == "ga-restart"]
    assert restarts[0] == 5  # generations 1–5 brought no improvement over generation 0
    assert (np.diff(sorted(set(restarts))) >= ga.config.stagnation_gens).all()
    np.testing.assert_array_equal(ga.best_x, first.x)
    assert ga.best_fitness == 0.1
    # once the restart batch is told, the population is the best plus the fresh samples
    ga2 = AVFuzzer(CROSSING, seed=3)
    ga2.tell(ga2.propose().x, 0.1)
    prop = ga2.propose()
    while prop.kind != "ga-restart":
        ga2.tell(prop.x, 0.5)
        prop = ga2.propose()
    fresh = []
    while prop.kind == "ga-restart":
        fresh.append(prop.x)
        ga2.tell(prop.x, 0.5)
        prop = ga2.propose()
    np.testing.assert_array_equal(ga2.population, np.vstack([first.x, *fresh]))
    np.testing.assert_array_equal(ga2.population_fitness, [0.1, 0.5, 0.5, 0.5])
    assert ga2.last_restart == 5


def test_no_restart_while_the_best_keeps_improving():
    ga = AVFuzzer(CROSSING, seed=0)
    counter = iter(range(10_000))
    log = _drive(ga, lambda x, kind: 1.0 - 1e-4 * next(counter), 200)
    assert "ga-restart" not in {kind for _, kind, _, _ in log}


def test_local_search_starts_at_generation_last_restart_plus_three():
    ga = AVFuzzer(CROSSING, seed=3)
    ga.tell(ga.propose().x, 0.1)
    log = _drive(ga, lambda x, kind: 0.5, 200)
    local_gens = sorted({gen for _, kind, gen, _ in log if kind == "ga-local"})
    restart = min(gen for _, kind, gen, _ in log if kind == "ga-restart")
    assert local_gens[0] == 3
    assert [g for g in local_gens if g > restart][0] == restart + 3
    assert not [g for g in local_gens if restart <= g < restart + 3]


def test_local_search_mutates_copies_of_the_best_and_a_better_result_joins_the_population():
    ga = AVFuzzer(HIGHWAY, seed=8)
    log = []
    while not log or log[-1][1] != "ga-local":
        prop = ga.propose()
        best_before = ga.best_x
        log.append((prop.x, prop.kind))
        if prop.kind != "ga-local":
            ga.tell(prop.x, 0.5 + (0.01 * len(log)) % 0.4)
    # the first LIS batch: copies of the best with exactly one gene redrawn
    assert np.sum(log[-1][0] != best_before) == 1
    ga.tell(log[-1][0], 0.01)  # far better than anything seen
    winner = log[-1][0]
    while True:
        prop = ga.propose()
        if prop.kind == "ga":  # the LIS is over and a new generation began
            break
        ga.tell(prop.x, 0.9)
    np.testing.assert_array_equal(ga.best_x, winner)
    assert ga.population_fitness.min() == 0.01
    assert any(np.array_equal(row, winner) for row in ga.population)


@pytest.mark.parametrize("space", [HIGHWAY, CROSSING], ids=["highway", "crossing"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_ga_improves_its_best_so_far_against_a_synthetic_criticality(space, seed):
    hidden = np.random.default_rng(100 + seed).uniform(size=space.dim)
    ga = AVFuzzer(space, seed=seed)
    log = _drive(ga, _distance_to(space, hidden), 60)
    initial_best = min(f for _, kind, _, f in log if kind == "ga-init")
    assert ga.best_fitness < initial_best
    assert ga.best_fitness == min(f for *_, f in log)


def test_same_seed_same_results_same_proposals():
    fit = _distance_to(HIGHWAY, np.full(HIGHWAY.dim, 0.3))
    a = _drive(AVFuzzer(HIGHWAY, seed=4), fit, 80)
    b = _drive(AVFuzzer(HIGHWAY, seed=4), fit, 80)
    c = _drive(AVFuzzer(HIGHWAY, seed=5), fit, 80)
    np.testing.assert_array_equal([r[0] for r in a], [r[0] for r in b])
    assert not np.array_equal([r[0] for r in a], [r[0] for r in c])


def _parallel(ga, fit, n_batches):
    """A loop that simulates whole batches at once and records results in completion order."""
    recorded = []
    for _ in range(n_batches):
        batch = [ga.propose() for _ in range(ga.available())]
        for prop in reversed(batch):  # finished in reverse order
            f = fit(prop.x)
            ga.tell(prop.x, f)
            recorded.append((prop.x, f))
    return recorded


def test_resume_after_out_of_order_results_and_lost_runs():
    fit = _distance_to(CROSSING, np.full(CROSSING.dim, 0.7))
    whole = AVFuzzer(CROSSING, seed=6)
    done = _parallel(whole, fit, 30)
    in_flight = [whole.propose() for _ in range(whole.available())]
    # the crash: the loop recorded `done` and the first in-flight run; the rest was lost
    f0 = fit(in_flight[0].x)
    resumed = AVFuzzer(CROSSING, seed=6)
    resumed.replay(
        np.array([x for x, _ in done] + [in_flight[0].x]), np.array([f for _, f in done] + [f0])
    )
    again = [resumed.propose() for _ in range(resumed.available())]
    np.testing.assert_array_equal([p.x for p in again], [p.x for p in in_flight[1:]])
    # both continue identically once the lost runs are simulated
    whole.tell(in_flight[0].x, f0)
    for p in again:
        whole.tell(p.x, fit(p.x))
        resumed.tell(p.x, fit(p.x))
    np.testing.assert_array_equal(
        [x for x, _ in _parallel(whole, fit, 10)], [x for x, _ in _parallel(resumed, fit, 10)]
    )
    assert resumed.best_fitness == whole.best_fitness


def test_replay_refuses_a_history_from_another_seed():
    fit = _distance_to(CROSSING, np.full(CROSSING.dim, 0.5))
    log = _drive(AVFuzzer(CROSSING, seed=1), lambda x, k: fit(x), 10)
    with pytest.raises(StrategyError, match="cannot resume"):
        AVFuzzer(CROSSING, seed=2).replay(
            np.array([r[0] for r in log]), np.array([r[3] for r in log])
        )


def test_ask_tell_misuse_is_refused():
    ga = AVFuzzer(CROSSING, seed=0)
    batch = [ga.propose() for _ in range(ga.available())]
    assert len(batch) == 4 and ga.available() == 0
    with pytest.raises(StrategyError, match="in flight"):
        ga.propose()
    with pytest.raises(StrategyError, match="not in flight"):
        ga.tell(CROSSING.sample(np.random.default_rng(99)), 0.5)
    with pytest.raises(StrategyError, match="finite"):
        ga.tell(batch[0].x, float("nan"))


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    told=st.lists(st.floats(0.0, 1.0), min_size=1, max_size=120),
    scenario=st.sampled_from(sorted(SCENARIOS)),
)
def test_ga_proposals_always_lie_inside_the_space(seed, told, scenario):
    space = get_scenario(scenario)
    ga = AVFuzzer(space, seed=seed)
    for f in told:
        x = ga.propose().x
        space.validate(x)
        ga.tell(x, f)
