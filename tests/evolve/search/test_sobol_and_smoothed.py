"""`sobol` covers X more evenly than Uniform; the smoothed-feedback loops steer by predicted f."""

import numpy as np
from scipy.stats import qmc
from sklearn.metrics import roc_auc_score

from evoeye.evolve.search import Records, make_strategy
from evoeye.evolve.search.feedback import normalise_feedback
from evoeye.evolve.search.mutation import EPSILON, regional_potential
from evoeye.evolve.search.smoothed import KNN_K
from evoeye.scenarios import DEFAULT_DELTA, get_scenario

CROSSING = get_scenario("unprotected-intersection")  # 10 parameters
HIGHWAY = get_scenario("highway-cut-in")  # 20 parameters


def _proposals(name, space, seed, n):
    strategy = make_strategy(name, space, seed)
    return np.stack([strategy.propose(None).x for _ in range(n)])


def test_sobol_spreads_its_runs_more_evenly_than_uniform_and_stays_in_range():
    def discrepancy(name, seed):
        x = _proposals(name, HIGHWAY, seed, 128)
        assert (x >= HIGHWAY.low).all() and (x <= HIGHWAY.high).all()
        return qmc.discrepancy(HIGHWAY.normalise(x))

    sobol = [discrepancy("sobol", s) for s in range(3)]
    uniform = [discrepancy("uniform", s) for s in range(3)]
    assert max(sobol) < min(uniform)


def test_sobol_proposals_do_not_depend_on_how_far_ahead_the_sequence_was_drawn():
    """Proposal 70 after the prefix of 64 points was doubled equals a fresh strategy's 70th."""
    whole = _proposals("sobol", CROSSING, 3, 71)
    resumed = make_strategy("sobol", CROSSING, 3)
    resumed.replay(whole[:70], np.ones(70))
    np.testing.assert_array_equal(resumed.propose(None).x, whole[70])
    assert len(np.unique(whole, axis=0)) == 71


def test_knn_potential_is_mean_plus_std_of_the_nearest_records_feedback():
    rng = np.random.default_rng(0)
    u = rng.uniform(size=(60, CROSSING.dim))
    feedback = rng.uniform(size=60)
    records = Records(CROSSING.denormalise(u), feedback)
    p = make_strategy("evoeye-knn", CROSSING, seed=0).exploit_probabilities(records)
    fbar = normalise_feedback(feedback)
    cheb = np.abs(u[:, None, :] - u[None, :, :]).max(axis=2)  # (60, 60)
    near = np.argsort(cheb, axis=1, kind="stable")[:, :KNN_K]
    q = fbar[near].mean(axis=1) + fbar[near].std(axis=1)
    np.testing.assert_allclose(p, (q + EPSILON) / (q.max() + EPSILON))


def test_in_many_dimensions_knn_smooths_where_the_delta_box_sees_only_the_record_itself():
    """In 20 dimensions q_δ is (almost) each record's own f̄ ± 0; the kNN potential is not."""
    rng = np.random.default_rng(1)
    u = rng.uniform(size=(200, HIGHWAY.dim))
    fbar = rng.uniform(size=200)
    q_delta = regional_potential(u, fbar, DEFAULT_DELTA)
    np.testing.assert_allclose(q_delta, fbar)  # S_δ(x) = {x}
    p_knn = make_strategy("evoeye-knn", HIGHWAY, 0).exploit_probabilities(
        Records(HIGHWAY.denormalise(u), fbar))
    assert abs(np.corrcoef(p_knn, fbar)[0, 1]) < 0.5


def test_under_noisy_feedback_the_smoothed_potentials_find_the_error_region():
    """f = 0.3 in a region (u0, u1 < 0.4) + U(0, 1) noise: the δ-box's p is each record's own
    noisy f; the forest's, learnt from the others, ranks the region's records higher (AUROC of
    p against membership), and the kNN's ranks them above chance."""
    auroc = {"evoeye": [], "evoeye-knn": [], "evoeye-forest": []}
    for seed in range(3):
        rng = np.random.default_rng(seed)
        u = rng.uniform(size=(300, CROSSING.dim))
        region = (u[:, 0] < 0.4) & (u[:, 1] < 0.4)
        records = Records(CROSSING.denormalise(u), 0.3 * region + rng.uniform(size=300))
        for name, got in auroc.items():
            p = make_strategy(name, CROSSING, 0).exploit_probabilities(records)
            got.append(roc_auc_score(region, p))
    assert min(auroc["evoeye-forest"]) > max(auroc["evoeye"])
    assert min(auroc["evoeye-knn"]) > 0.6


def test_the_forest_potential_does_not_see_a_records_own_feedback():
    """One record with a high f among zeros: out-of-bag, its own potential stays low."""
    rng = np.random.default_rng(2)
    u = rng.uniform(size=(80, CROSSING.dim))
    feedback = np.zeros(80)
    feedback[0] = 1.0
    p = make_strategy("evoeye-forest", CROSSING, 0).exploit_probabilities(
        Records(CROSSING.denormalise(u), feedback))
    assert p[0] < 0.5 * p.max()
