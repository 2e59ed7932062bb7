"""The study's checkpoint monitor as an ensemble: one member is today's monitor, more members
are distinct networks scored by their mean, calibrated by the shared calibrator."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

import evoeye.monitor.ensemble as ensemble_module
from evoeye.monitor.calibration import calibrate_on_validation
from evoeye.monitor.ensemble import EnsembleMonitor, member_seeds
from evoeye.monitor.fusion import FusionMonitor
from evoeye.paths import DataRoot
from evoeye.results.efficiency.acquire import PoolAcquirer
from evoeye.results.efficiency.curves import run_curve
from evoeye.results.efficiency.learner import Learner
from evoeye.results.efficiency.oracle import run_oracle
from evoeye.results.efficiency.report import learner_words
from evoeye.results.ledger import Ledger

SEED = 7


def _learner(context, members: int) -> Learner:
    return replace(context.learner, members=members)


def _train(context):
    return context.bank.windows(context.bank.pool.scenario_id[:20])


def _keys(ctx, monkeypatch) -> list[tuple[str, dict]]:
    """Every ledger unit's kind and inputs, as the curve asks for them."""
    asked, real = [], ctx.ledger.remember
    monkeypatch.setattr(ctx.ledger, "remember", lambda kind, inputs, compute:
                        asked.append((kind, dict(inputs))) or real(kind, inputs, compute))
    return asked


def test_one_member_is_the_single_monitor_and_keys_nothing_new(context, tmp_path,
                                                               monkeypatch) -> None:
    """members = 1: the checkpoint's monitor is `scratch`'s, and a curve asks the ledger for
    the units it always did (no members key): the same files, the same figures."""
    train, test = _train(context), context.learner.judging["test"]
    one = _learner(context, 1).checkpoint(train, SEED)
    assert isinstance(one, FusionMonitor)
    assert np.array_equal(one.score(test), context.learner.scratch(train, SEED).score(test))
    ctx = replace(context, ledger=Ledger(DataRoot.resolve(tmp_path / "fresh")))
    asked = _keys(ctx, monkeypatch)
    curve = run_curve(ctx, "uniform", 0, PoolAcquirer(ctx.bank))
    assert {kind for kind, _ in asked} == {"efficiency-curve", "efficiency-scratch"}
    assert not any("members" in inputs for _, inputs in asked)
    scratch_keys = {tuple(sorted(i)) for kind, i in asked if kind == "efficiency-scratch"}
    assert scratch_keys == {("n", "recipe", "regime", "runs", "seed", "sets")}
    assert learner_words(ctx.config.to_dict()) == ""  # the page reads as it did
    assert curve == run_curve(context, "uniform", 0, PoolAcquirer(context.bank))


def test_three_members_differ_and_the_ensemble_scores_their_mean(context) -> None:
    train, test = _train(context), context.learner.judging["test"]
    ens = _learner(context, 3).checkpoint(train, SEED)
    assert isinstance(ens, EnsembleMonitor) and len(ens.members) == 3
    scores = ens.member_scores(test)  # (3, B)
    assert all(not np.array_equal(scores[i], scores[j]) for i, j in ((0, 1), (0, 2), (1, 2)))
    assert np.array_equal(scores[0], context.learner.scratch(train, SEED).score(test))
    for member, seed in zip(ens.members[1:], member_seeds(SEED, 3)[1:], strict=True):
        assert np.array_equal(member.score(test),
                              context.learner.scratch(train, seed).score(test))
    assert np.allclose(ens.score(test), scores.astype(np.float64).mean(axis=0), rtol=0,
                       atol=1e-12)
    again = _learner(context, 3).checkpoint(train, SEED)
    assert np.array_equal(again.score(test), ens.score(test))  # seeded: the same ensemble


def test_the_ensembles_thresholds_come_from_the_shared_calibrator(context,
                                                                   monkeypatch) -> None:
    """The ensemble's thresholds are `calibrate_on_validation` of its own mean scores of the
    validation set: the function `fit_windows` calibrates a single monitor with."""
    calls = []

    def spy(scores, val, *args):
        calls.append(np.asarray(scores).copy())
        return calibrate_on_validation(scores, val, *args)

    monkeypatch.setattr(ensemble_module, "calibrate_on_validation", spy)
    val = context.learner.val
    ens = _learner(context, 3).checkpoint(_train(context), SEED)
    assert len(calls) == 1 and np.array_equal(calls[0], ens.score(val))
    assert ens.thresholds == calibrate_on_validation(ens.score(val), val)
    assert ens.thresholds != ens.members[0].thresholds  # not a member's


def test_an_ensemble_curve_is_keyed_apart_and_judged_as_an_ensemble(context, tmp_path,
                                                                   monkeypatch) -> None:
    ctx = replace(context, config=replace(context.config, members=2),
                  learner=_learner(context, 2),
                  ledger=Ledger(DataRoot.resolve(tmp_path / "k2")))
    asked = _keys(ctx, monkeypatch)
    curve = run_curve(ctx, "uniform", 0, PoolAcquirer(ctx.bank))
    assert asked and all(inputs.get("members") == 2 for _, inputs in asked)
    single = run_curve(context, "uniform", 0, PoolAcquirer(context.bank))
    assert curve["acquired_ids"] == single["acquired_ids"]  # the same runs (uniform is blind)
    assert curve["budgets"]["10"]["scratch"] != single["budgets"]["10"]["scratch"]
    # the per-round monitor starts from G_0's member 0: the single monitor's G_0
    assert curve["budgets"]["6"]["update"] == single["budgets"]["6"]["scratch"]
    assert curve["budgets"]["6"]["scratch"] != single["budgets"]["6"]["scratch"]
    assert "2 members" in " ".join(learner_words(ctx.config.to_dict()).split())


def test_the_oracles_candidates_are_ensembles_and_keyed_apart(context, tmp_path,
                                                              monkeypatch) -> None:
    ctx = replace(context, config=replace(context.config, members=2, checkpoints=(10,),
                                          oracle_candidates=4),
                  learner=_learner(context, 2),
                  ledger=Ledger(DataRoot.resolve(tmp_path / "oracle")))
    built = []
    real = Learner.checkpoint
    monkeypatch.setattr(Learner, "checkpoint", lambda self, *a, **k:
                        built.append(m := real(self, *a, **k)) or m)
    asked = _keys(ctx, monkeypatch)
    curve = run_oracle(ctx, 0, control=True)  # its control: exactly oracle_candidates
    assert all(isinstance(m, EnsembleMonitor) and len(m.members) == 2 for m in built)
    assert len(built) == 1 + 4  # G_0, and each candidate of the one step
    assert asked and all(inputs.get("members") == 2 for _, inputs in asked)
    assert curve["budgets"]["10"]["scratch"] in [ctx.learner.judge(m) for m in built[1:]]
