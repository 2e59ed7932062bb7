"""A tiny regime of synthetic runs (both classes in every set), and its study context."""

from __future__ import annotations

import json

import pytest

from evoeye.log.synthetic import SCENARIO, write_synthetic_batch
from evoeye.monitor.train import TrainParams
from evoeye.paths import DataRoot
from evoeye.results.efficiency.acquire import Bank
from evoeye.results.efficiency.config import EfficiencyConfig
from evoeye.results.efficiency.curves import Context
from evoeye.results.efficiency.data import BOUNDARY_FILE, batch_name, regime_root
from evoeye.results.efficiency.learner import Learner
from evoeye.results.efficiency.runner import sets_fingerprint
from evoeye.results.efficiency.sets import JUDGING_SETS, RegimeData
from evoeye.results.ledger import Ledger
from evoeye.scenarios import get_scenario
from evoeye.store import ingest

TINY = EfficiencyConfig(regimes=(SCENARIO,), strategies=("uniform", "boundary", "evoeye"),
                        seeds=(0, 1), initial_runs=6, checkpoints=(10, 14),
                        reference_checkpoints=(18,), n_round=4, pool_runs=40, test_runs=8,
                        val_runs=8, oracle_runs=6, boundary_pairs=2, boundary_steps=1,
                        oracle_candidates=4, epochs=1, patience=1)
SIZES = {"pool": 40, "test": 8, "val": 8, "oracle": 6}


@pytest.fixture(scope="session")
def tiny_regime(tmp_path_factory) -> tuple[DataRoot, DataRoot]:
    """(study root, the regime's root) with the regime's sets ingested."""
    root = DataRoot.resolve(tmp_path_factory.mktemp("study") / "data")
    data = regime_root(root, SCENARIO)
    for i, (name, n) in enumerate(SIZES.items()):
        write_synthetic_batch(data, batch_name(name, TINY), n, first_seed=1000 * i,
                              n_frames=40, collision_frame=30)
    write_synthetic_batch(data, "boundary", 4, first_seed=9000, n_frames=40, collision_frame=30)
    ingest(data)
    ids = [f"boundary-{i:02d}" for i in range(4)]
    (data.path / BOUNDARY_FILE).write_text(json.dumps({"scenario_ids": ids}))
    return root, data


@pytest.fixture
def tiny_config() -> EfficiencyConfig:
    return TINY


@pytest.fixture
def context(tiny_regime) -> Context:
    root, data = tiny_regime
    sets = RegimeData.load(data, TINY)
    learner = Learner(sets.sets["val"], {k: sets.sets[k] for k in JUDGING_SETS},
                      TrainParams(**TINY.train_overrides))
    return Context(SCENARIO, get_scenario(SCENARIO), TINY, learner, Bank(sets), Ledger(root),
                   sets_fingerprint(sets))
