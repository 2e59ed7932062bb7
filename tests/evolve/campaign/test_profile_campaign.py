"""A campaign's regime: it acquires under the ADS profile of its initial runs, and only one."""

from __future__ import annotations

import pytest

from evoeye.batch import plan_uniform, run_batch
from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.campaign.state import MixedProfilesError, read_initial
from evoeye.monitor import train_monitor
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec, Warehouse, ingest

SCENARIO = "unprotected-intersection"
SPLITS = SplitSpec(seed=0, train_frac=0.5, val_frac=0.25)


def test_a_campaign_acquires_under_the_profile_of_its_initial_runs(tmp_path) -> None:
    highway = "highway-cut-in"  # firm-yield changes only yielding: 10 of these 16 runs collide
    data = DataRoot.resolve(tmp_path / "data")
    run_batch(plan_uniform(highway, 16, 6, ads="firm-yield"), data)
    ingest(data)
    g0 = train_monitor(data, highway, seed=0, splits=SPLITS, epochs=1)
    config = CampaignConfig(highway, strategy="uniform", budget_s=1000.0, seed=0, monitor=g0,
                            n_round=2, epochs=1, splits=SPLITS)
    Campaign(data, config).run(max_rounds=1)
    rows = Warehouse(data).sql("SELECT round, ads_profile, count(*) AS n FROM scenarios "
                               "GROUP BY ALL ORDER BY ALL").to_pylist()
    assert rows == [{"round": 0, "ads_profile": "firm-yield", "n": 16},
                    {"round": 1, "ads_profile": "firm-yield", "n": 2}]


def test_initial_runs_of_two_profiles_are_refused(root_copy) -> None:
    root = root_copy("mixed")  # the seeded root's runs are the default profile's
    run_batch(plan_uniform(SCENARIO, 8, 6, ads="firm-yield"), root)
    ingest(root)
    with pytest.raises(MixedProfilesError, match="default, firm-yield"):
        read_initial(root, SCENARIO, SPLITS)
