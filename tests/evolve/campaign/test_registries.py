"""A new monitor family and a new acquisition strategy, added through their registries alone.

Nothing outside this file names them: registering is all it takes for a campaign to evolve the
family and run the strategy, for the RQ1 evaluation to load the family's versions, and for the
RQ2 experiment and its report to list both (docs/extending.md).
"""

from __future__ import annotations

import hashlib
import json
import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest

from evoeye.evaluation.monitors import load_monitors
from evoeye.evolve.campaign.config import CampaignConfig, check_known
from evoeye.evolve.campaign.experiment import methods, run_experiment
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.campaign.report import markdown
from evoeye.evolve.search import STRATEGIES, Proposal, Records
from evoeye.monitor.card import thresholds_from_json
from evoeye.monitor.families import FAMILIES, MonitorFamily, family_of
from evoeye.monitor.protocol import Thresholds
from evoeye.paths import DataRoot
from evoeye.scenarios import LogicalScenario
from evoeye.store import SplitSpec, load_windows
from evoeye.store.feedback import read_feedback, read_rounds

SCENARIO = "unprotected-intersection"  # of the `seeded` data root (conftest.py)
SPLITS = SplitSpec(seed=0, train_frac=0.5, val_frac=0.25)


# -- a toy monitor family: the unsafe share of its training frames, everywhere -----------------
@dataclass
class ConstantRisk:
    version: str
    risk: float
    thresholds: Thresholds | None
    card: dict[str, Any] = field(default_factory=dict)
    name: str = "toy"
    context_len: int = 1

    def score(self, windows) -> np.ndarray:
        return np.full(len(windows), self.risk)


def train_toy(root: DataRoot, scenario: str, *, train_runs, val_runs, seed: int = 0,
              init_from: str | None = None, horizon_s: float = 3.0, **_other: Any) -> str:
    risk = float(load_windows(root, train_runs, context_len=1, horizon_s=horizon_s).label.mean())
    model = json.dumps(risk).encode()
    version = "toy-" + hashlib.sha256(model + f"{seed}{init_from}".encode()).hexdigest()[:12]
    folder = TOY.version_dir(root, version)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / TOY.model_file).write_bytes(model)
    (folder / TOY.meta_file).write_text(json.dumps({
        "model_sha256": hashlib.sha256(model).hexdigest(), "parent": init_from,
        "logical_scenario": scenario, "thresholds": {"0.05": risk, "0.01": risk}}))
    return version


def decode_toy(data: bytes, meta: dict[str, Any], version: str) -> ConstantRisk:
    return ConstantRisk(version, json.loads(data), thresholds_from_json(meta["thresholds"]), meta)


def initial_toy(root: DataRoot, scenario: str, *, train_runs, val_runs, horizon_s: float,
                recipe: str | None = None) -> str:  # a toy has no training recipe
    return train_toy(root, scenario, train_runs=list(train_runs), val_runs=val_runs,
                     horizon_s=horizon_s)


TOY = MonitorFamily("toy", "Toy", "toy-", "baselines/toy", "risk.json", "meta.json",
                    decode=decode_toy, train=train_toy, initial=initial_toy)


# -- a toy acquisition strategy: the lower corner of the space, then the upper, in turn -------
class Corners:
    name = "corners"

    def __init__(self, space: LogicalScenario, seed: int, **_options: Any) -> None:
        self.space, self.proposals = space, 0

    def propose(self, records: Records) -> Proposal:
        corner = self.space.low if self.proposals % 2 == 0 else self.space.high
        self.proposals += 1
        return Proposal(x=corner.copy(), kind="corner")

    def tell(self, x: np.ndarray, fitness: float) -> None:
        pass

    def available(self) -> int:
        return sys.maxsize

    def replay(self, params: np.ndarray, fitness: np.ndarray) -> None:
        self.proposals = len(params)


@pytest.fixture
def registered(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(FAMILIES, "toy", TOY)
    monkeypatch.setitem(STRATEGIES, "corners", Corners)


def test_unregistered_names_are_refused() -> None:
    with pytest.raises(ValueError, match="unknown family 'toy'"):
        CampaignConfig(SCENARIO, family="toy")
    with pytest.raises(ValueError, match="unknown strategy 'corners'"):
        CampaignConfig(SCENARIO, strategy="corners")


def test_a_registered_family_and_strategy_are_evolved_assessed_and_reported(
        registered, root_copy, seeded) -> None:
    root = root_copy("toys")
    assert {"toy-evo", "corners"} <= set(methods())
    check_known("method", ["toy-evo", "corners"])
    # a campaign evolves the toy family, from its own G_0, round by round
    cfg = CampaignConfig(SCENARIO, family="toy", strategy="uniform", budget_s=1000.0,
                         n_round=2, splits=SPLITS, update="finetune")  # trained on every record
    campaign = Campaign(root, cfg)
    assert campaign.campaign_id.startswith("evo-toy-uniform-s0-")
    assert campaign.g0.startswith("toy-") and campaign.reference == seeded[1]
    state = campaign.run(max_rounds=1)
    rows = read_rounds(root, campaign.campaign_id)
    g1 = rows[1].monitor_version
    assert g1.startswith("toy-") and g1 != rows[0].monitor_version
    assert family_of(g1) is TOY and (monitor := load_monitors(root, [g1])[0]).card["parent"]
    ids = [str(s) for s, ok in zip(state.records.scenario_id, state.ok, strict=True) if ok]
    assert monitor.risk == pytest.approx(load_windows(root, ids, context_len=1).label.mean())
    fb = read_feedback(root, g1, "raw")  # f_{r+1} of every record under the toy G_1
    assert set(fb.column("scenario_id").to_pylist()) == set(ids)
    # the corners strategy acquires the corners of the space, in turn
    corners = Campaign(root, CampaignConfig(SCENARIO, strategy="corners", monitor=seeded[1],
                                            seed=1, budget_s=1000.0, n_round=2, epochs=1,
                                            splits=SPLITS)).run(max_rounds=1)
    new = corners.records.tail(corners.n_init).params
    np.testing.assert_allclose(new, [campaign.space.low, campaign.space.high])
    # the RQ2 experiment runs both methods and its report lists them
    results = run_experiment(root, [SCENARIO], CampaignConfig(SCENARIO, splits=SPLITS, epochs=1),
                             strategies=["corners", "toy-evo"], seeds=[0], budget_s=40.0,
                             controls=0, progress=lambda msg: None)
    res = results[SCENARIO]
    assert res["toy-evo"][0]["rounds"][-1]["version"].startswith("toy-")
    assert res["corners"][0]["acquisition"]["runs"] >= 1
    md = markdown(results)
    assert "| corners |" in md and "| toy-evo |" in md and "| Toy (Toy-Evo's G_0) |" in md
