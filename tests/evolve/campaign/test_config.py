"""A campaign's options: declared once in CampaignConfig, read by the command line and the flows."""

from __future__ import annotations

import dataclasses
import hashlib
import inspect
import json
import subprocess
import sys
from dataclasses import replace

import pytest

from evoeye.evolve.campaign.config import (
    CampaignConfig,
    campaign_id,
    campaign_options,
    config_from,
    option_values,
)
from evoeye.seeds import STREAMS_VERSION
from evoeye.splits import SplitSpec


def test_literal_defaults_equal_their_sources() -> None:
    from evoeye.evolve.campaign import config
    from evoeye.monitor.families import DEFAULT_FAMILY
    from evoeye.monitor.recipes import DEFAULT_RECIPE, LEGACY_RECIPE
    from evoeye.scenarios import DEFAULT_DELTA
    from evoeye.sim.runner import SimConfig
    from evoeye.store.windows import DEFAULT_HORIZON_S

    literal = {"delta": config.DEFAULT_DELTA, "horizon_s": config.DEFAULT_HORIZON_S,
               "max_run_s": config.MAX_RUN_S, "family": config.DEFAULT_FAMILY,
               "recipes": (config.DEFAULT_RECIPE, config.LEGACY_RECIPE)}
    assert literal == {"delta": DEFAULT_DELTA, "horizon_s": DEFAULT_HORIZON_S,
                       "max_run_s": SimConfig().duration_s, "family": DEFAULT_FAMILY,
                       "recipes": (DEFAULT_RECIPE, LEGACY_RECIPE)}


def test_the_config_module_imports_nothing_heavy() -> None:
    probe = ("import json, sys; import evoeye.evolve.campaign.config; "
             "print(json.dumps(sorted({m.split('.')[0] for m in sys.modules})))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          check=True)
    loaded = set(json.loads(done.stdout))
    assert "evoeye" in loaded
    assert not loaded & {"numpy", "torch", "duckdb", "pyarrow", "highway_env", "prefect"}


def test_options_are_the_fields_with_the_split_flattened_and_round_trip() -> None:
    names = [o.name for o in campaign_options()]
    assert names[:3] == ["scenario", "strategy", "budget_s"]
    assert names[-4:] == ["split_seed", "train_frac", "val_frac", "test_batch"]
    assert "splits" not in names and "max_run_s" not in names  # flattened; internal
    cfg = CampaignConfig("unprotected-intersection", strategy="uniform", budget_s=90.0, seed=3,
                         n_round=4, epochs=2, feedback="prior-corrected", delta=0.1,
                         splits=SplitSpec(7, 0.6, 0.2, "held-out"))
    values = option_values(cfg)
    assert values["split_seed"] == 7 and values["val_frac"] == 0.2
    assert values["test_batch"] == "held-out"
    assert next(o for o in campaign_options() if o.name == "test_batch").optional
    assert config_from(values) == cfg
    assert "seed" not in option_values(cfg, exclude=("seed",))
    with pytest.raises(ValueError, match="max_run_s is no campaign option"):
        option_values(replace(cfg, max_run_s=5.0))


@pytest.mark.parametrize(("field", "value", "message"), [
    ("n_round", 0, "n_round must be >= 1"), ("budget_s", -1.0, "budget_s must be >= 0"),
    ("delta", 0.0, "delta must be > 0"), ("delta", 1.5, "delta must be <= 1"),
    ("strategy", "random-walk", "unknown strategy 'random-walk'"),
    ("scenario", "roundabout", "unknown scenario 'roundabout'"),
    ("family", "context-only", "unknown family 'context-only'"),  # not evolvable
])
def test_bad_values_are_refused_naming_the_field(field: str, value, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        CampaignConfig(**{field: value})


def test_the_cli_commands_and_the_flows_take_every_option() -> None:
    from typer.main import get_command

    from evoeye.cli import app
    from flows.evolve import EvolveParams
    from flows.experiment import PER_CAMPAIGN, ExperimentParams

    options = {o.name for o in campaign_options()}
    commands = get_command(app).commands
    evolve_cli = {p.name for p in commands["evolve"].params}
    experiment_cli = {p.name for p in commands["experiment"].params}
    assert options <= evolve_cli and options <= set(EvolveParams.model_fields)
    shared = options - set(PER_CAMPAIGN)
    assert shared <= experiment_cli and shared <= set(ExperimentParams.model_fields)
    assert "scenarios" in ExperimentParams.model_fields and "scenario" in experiment_cli
    # the flow's defaults and bounds are the config's
    field = EvolveParams.model_fields["n_round"]
    assert field.default == CampaignConfig().n_round
    assert any(getattr(m, "ge", None) == 1 for m in field.metadata)
    help_of = {p.name: p.help for p in commands["evolve"].params}
    assert help_of["budget_s"] == inspect.cleandoc(
        next(o.help for o in campaign_options() if o.name == "budget_s"))


def test_keep_parent_reaches_a_fine_tuned_update_only_and_adds_nothing_when_off() -> None:
    base = CampaignConfig("highway-cut-in", update="replay")
    kept = replace(base, keep_parent=True)
    assert "keep_parent" not in base.train_overrides()
    assert kept.train_overrides() == {**base.train_overrides(), "keep_parent": True}
    assert "keep_parent" not in replace(kept, update="retrain").train_overrides()

    def cid(config: CampaignConfig) -> str:
        return campaign_id(config, "fusion-x", ["a", "b"], feedback_blind=False, committee=False)

    # off, the option adds nothing to the id (the seed streams' version is hashed in: seeds.py)
    legacy = {k: v for k, v in dataclasses.asdict(base).items()
              if k not in ("budget_s", "reference", "feedback", "family", "committee",
                           "keep_parent", "importance_weights")}
    legacy.update(monitor="fusion-x", initial=hashlib.sha256(b"a\nb").hexdigest(),
                  streams=STREAMS_VERSION)
    digest = hashlib.sha256(json.dumps(legacy, sort_keys=True).encode()).hexdigest()[:10]
    assert cid(base) == f"evo-evoeye-s0-{digest}" != cid(kept)


def test_importance_weights_reach_every_update_and_add_nothing_to_the_id_when_off() -> None:
    base = CampaignConfig("highway-cut-in", strategy="ce-is")
    weighted = replace(base, importance_weights=True)
    assert "importance_weights" not in base.train_overrides()
    assert weighted.train_overrides() == {**base.train_overrides(), "importance_weights": True}

    def cid(config: CampaignConfig) -> str:
        return campaign_id(config, "fusion-x", ["a"], feedback_blind=True, committee=False)

    assert cid(base) != cid(weighted)  # off: nothing in the id (the keep_parent test above)
    with pytest.raises(ValueError, match="importance weights train FusionMonitors"):
        CampaignConfig("highway-cut-in", family="aem", importance_weights=True)
