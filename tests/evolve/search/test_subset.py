"""`subset`: levels conditioned towards the failures, an estimate near P, resume, refusals."""

import numpy as np
import pytest

from evoeye.evolve.search import Records, StrategyError, make_strategy
from evoeye.evolve.search.subset import Walk, subset_estimate
from evoeye.scenarios import get_scenario

HIGHWAY = get_scenario("highway-cut-in")
CHAINS = 10


def level(space, x, p):
    """Synthetic: a failure (0) in the corner u0 > 1 − √p, u1 < √p (p-mass p), rising linearly
    away from it; the other dimensions do not matter."""
    u = space.normalise(x)
    a = np.sqrt(p)
    gap = np.maximum(1.0 - a - u[..., 0], 0.0) + np.maximum(u[..., 1] - a, 0.0)
    return np.where(gap <= 0.0, 0.0, 0.05 + gap)


def acquire(seed, n, p, records=None, strategy=None):
    strategy = strategy or make_strategy("subset", HIGHWAY, seed, batch=CHAINS)
    records = records or Records.empty(HIGHWAY.dim)
    props = []
    for _ in range(n):
        prop = strategy.propose(records)
        f = float(level(HIGHWAY, prop.x, p))
        strategy.tell(prop.x, f)
        records = records.append(prop.x, fitness=f, collided=f == 0.0, log_q=prop.log_q,
                                 log_p=prop.log_p)
        props.append(prop)
    return strategy, records, props


@pytest.mark.parametrize("p", [0.0016, 0.014])
def test_it_finds_far_more_failures_than_p_and_estimates_p(p):
    found, estimates = [], []
    for seed in range(30):
        _, records, _ = acquire(seed, 200, p)
        found.append(records.collided.sum())
        estimates.append(subset_estimate(records.fitness, records.collided, CHAINS))
    assert np.mean(found) >= 10 * 200 * p  # Uniform would find 200·p per seed
    # the estimate is near P: its mean within a third of it over 30 seeds (its bias is O(1/N))
    assert np.mean(estimates) == pytest.approx(p, rel=0.35)


def test_the_first_level_is_uniform_and_later_ones_are_chains_from_the_best():
    _, records, props = acquire(0, 90, 0.0016)
    n0 = Walk(CHAINS, 0.2).per_level
    assert n0 == 50  # c / p0 samples per level
    assert {p.kind for p in props[:n0]} == {"uniform"} and props[0].parent is None
    assert {p.kind for p in props[n0:]} == {"subset"}
    # the chains start at the c lowest levels of level 0
    best = set(np.argsort(records.fitness[:n0], kind="stable")[:CHAINS].tolist())
    assert {p.parent for p in props[n0:n0 + CHAINS]} == best
    # no proposal carries a density: subset runs have no importance weight
    assert all(p.log_q is None for p in props)


def test_the_walk_moves_only_inside_the_current_level():
    fitness = np.r_[np.linspace(0.9, 0.4, 50), [0.3] * 5 + [0.95] * 5]  # level 0 + one step
    collided = np.zeros(60, bool)
    w = Walk.replay(fitness, collided, CHAINS, 0.2)
    assert w.level == 1 and w.steps == 1
    assert w.threshold == pytest.approx(fitness[40])  # the 10th lowest of level 0
    # the five candidates under the threshold were accepted, the others left their chain put
    # (chain j starts at the j-th lowest: rows 49, 48, … 40)
    assert w.states[:5] == [50, 51, 52, 53, 54] and w.states[5:] == [44, 43, 42, 41, 40]
    assert w.accepted == 5


def test_the_estimate_freezes_once_a_level_holds_enough_failures():
    fitness = np.r_[np.zeros(12), np.full(38, 0.5)]  # 12 collisions in level 0's 50
    collided = fitness == 0.0
    assert subset_estimate(fitness, collided, CHAINS) == pytest.approx(12 / 50)
    more = np.r_[fitness, np.zeros(40)]  # the chains then walk inside F: every step a failure
    assert subset_estimate(more, more == 0.0, CHAINS) == pytest.approx(12 / 50)


def test_a_resumed_strategy_proposes_the_same_runs():
    _, records, props = acquire(3, 130, 0.014)
    head = records.head(125)  # resumed in the middle of a batch: the batch is rebuilt
    fresh = make_strategy("subset", HIGHWAY, 3, batch=CHAINS)
    fresh.replay(head.params, head.fitness)
    _, _, again = acquire(3, 5, 0.014, records=head, strategy=fresh)
    assert [p.x.tolist() for p in again] == [p.x.tolist() for p in props[125:130]]
    assert [p.parent for p in again] == [p.parent for p in props[125:130]]


def test_it_refuses_a_pool_and_a_bad_p0():
    pool = HIGHWAY.sample(np.random.default_rng(0), 50)
    s = make_strategy("subset", HIGHWAY, 0, batch=CHAINS, pool=pool)
    with pytest.raises(StrategyError, match="generative mode only"):
        s.propose(Records.empty(HIGHWAY.dim))
    with pytest.raises(StrategyError, match="p0 must be in"):
        make_strategy("subset", HIGHWAY, 0, p0=0.9)



def found_and_walk(name, seed, p, n=200):
    """The collisions strategy `name` finds in n runs at one seed, and its walk after them."""
    strategy = make_strategy(name, HIGHWAY, seed, batch=CHAINS)
    _, records, _ = acquire(seed, n, p, strategy=strategy)
    walk = Walk.replay(records.fitness, records.collided, CHAINS, strategy.p0,
                       strategy.distinct)
    return int(records.collided.sum()), walk


def test_subset_deep_goes_deeper_and_finds_more_where_subset_runs_out_of_budget():
    # p = 10⁻⁴: the levels of p0 = 0.2 that 200 runs allow stop at P(F_4) = 0.0016
    p, seeds = 1e-4, range(12)
    default = [found_and_walk("subset", seed, p) for seed in seeds]
    deep = [found_and_walk("subset-deep", seed, p) for seed in seeds]
    assert all(w.level <= 4 for _, w in default)
    assert all(w.level >= 9 for _, w in deep)  # 0.5⁹ ≈ 0.002: past p0 = 0.2's reach
    assert np.mean([f for f, _ in deep]) >= 5 * max(np.mean([f for f, _ in default]), 200 * p)
    assert sum(f > 0 for f, _ in deep) > sum(f > 0 for f, _ in default)


def test_subset_deep_is_subset_at_another_p0_and_subset_keeps_its_own():
    a = make_strategy("subset-deep", HIGHWAY, 5, batch=CHAINS, p0=0.2)
    _, _, deep = acquire(5, 120, 0.014, strategy=a)
    _, _, default = acquire(5, 120, 0.014)
    assert [q.x.tolist() for q in deep] == [q.x.tolist() for q in default]
    assert make_strategy("subset", HIGHWAY, 0).p0 == 0.2
    assert make_strategy("subset-deep", HIGHWAY, 0).p0 == 0.5
    assert Walk(CHAINS, 0.5).steps_per_level == 1 and Walk(CHAINS, 0.5).per_level == 20
    # subset-spread is subset-deep until a level's seeds would repeat a run
    _, _, deep = acquire(5, 200, 0.0016, strategy=make_strategy("subset-deep", HIGHWAY, 5,
                                                                 batch=CHAINS))
    _, _, spread = acquire(5, 200, 0.0016, strategy=make_strategy("subset-spread", HIGHWAY, 5,
                                                                   batch=CHAINS))
    same = [d.x.tolist() == s.x.tolist() for d, s in zip(deep, spread, strict=True)]
    assert all(same[:30]) and not all(same)


def test_subset_spread_seeds_its_chains_from_distinct_runs():
    # level 0 (20 runs), then one step in which only chain 0 (seeded at run 19) moved, to the
    # lowest run yet: in subset-deep's level every chain that stayed put counts twice (its seed
    # and its state), so five runs fill its ten seeds; subset-spread's are ten distinct runs,
    # and its threshold falls less
    fitness = np.r_[np.linspace(0.9, 0.3, 20), [0.1], [0.95] * 9]
    collided = np.zeros(30, bool)
    deep = Walk.replay(fitness, collided, CHAINS, 0.5)
    spread = Walk.replay(fitness, collided, CHAINS, 0.5, distinct=True)
    assert deep.level == spread.level == 2
    assert sorted(deep.states) == [15, 15, 16, 16, 17, 17, 18, 18, 19, 20]
    assert sorted(spread.states) == list(range(11, 21))
    assert spread.threshold == fitness[11] > deep.threshold == fitness[15]


def test_subset_spread_does_not_walk_inside_f_on_copies_of_one_failure():
    # one collision in level 0, then every candidate rejected: its copies double every level
    fitness = np.r_[[0.5] * 19, [0.0], [0.9] * 40]
    collided = fitness == 0.0
    deep = Walk.replay(fitness, collided, CHAINS, 0.5)
    spread = Walk.replay(fitness, collided, CHAINS, 0.5, distinct=True)
    assert deep.final and set(deep.states) == {19}  # every chain parked on the one failure
    assert not spread.final and len(set(spread.states)) == CHAINS


def test_subset_spread_finds_more_failures_than_p_and_reaches_them_on_every_seed():
    p = 0.0016
    found = [found_and_walk("subset-spread", seed, p)[0] for seed in range(12)]
    assert np.mean(found) >= 10 * 200 * p and min(found) > 0
