"""What the campaign tests share: the seeded root's scenario and splits, a small campaign's
config, and a snapshot of what a finished campaign leaves behind."""

from __future__ import annotations

from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.loop import Campaign
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec
from evoeye.store.feedback import read_committee, read_feedback, read_rounds

SCENARIO = "unprotected-intersection"  # ~half its runs collide: both classes in tiny splits
SPLITS = SplitSpec(seed=0, train_frac=0.5, val_frac=0.25)


def config(g0: str, **kw) -> CampaignConfig:
    base = dict(scenario=SCENARIO, strategy="evoeye", budget_s=1000.0, seed=0, monitor=g0,
                n_round=2, epochs=1, splits=SPLITS)
    return CampaignConfig(**{**base, **kw})


def snapshot(root: DataRoot, c: Campaign) -> dict:
    """Everything a finished campaign left behind that must not depend on interruptions."""
    rounds = read_rounds(root, c.campaign_id)
    fb = read_feedback(root)
    logs = sorted(p.name for p in (root.runs / SCENARIO / c.campaign_id).glob("*"))
    return {
        "rounds": [(r.round, r.monitor_version, list(r.scenario_ids), r.n_records,
                    r.simulated_s) for r in rounds],
        "logs": logs,
        "feedback": sorted(zip(fb.column("monitor_version").to_pylist(),
                               fb.column("feedback_mode").to_pylist(),
                               fb.column("scenario_id").to_pylist(),
                               fb.column("feedback").to_pylist(), strict=True)),
        "committee": read_committee(root, c.campaign_id),
    }
