"""The evolution campaign: Algorithm 1 on real (tiny) simulations, its budget, and resume."""

from __future__ import annotations

import gc
import shutil

import numpy as np
import pytest

from evoeye.evolve.campaign import loop as campaign_mod
from evoeye.evolve.campaign.config import (
    FINETUNE_EPOCHS,
    FINETUNE_PATIENCE,
    REPLAY_EPOCHS,
    REPLAY_PATIENCE,
    CampaignConfig,
)
from evoeye.evolve.campaign.loop import Campaign
from evoeye.monitor.families import FAMILIES
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec, Warehouse, load_windows
from evoeye.store.feedback import read_committee, read_feedback, read_rounds
from evoeye.store.log_windows import read_logged_run

SCENARIO = "unprotected-intersection"  # of the `seeded` data root (conftest.py)
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


def test_log_windows_equal_the_warehouse_windows(seeded) -> None:
    root, _ = seeded
    sid = Warehouse(root).sql("SELECT scenario_id FROM scenarios WHERE collided LIMIT 1"
                              ).column(0)[0].as_py()
    log = next(root.runs.rglob(f"{sid}.mcap"))
    mine = read_logged_run(log, context_len=5, horizon_s=3.0).windows
    ref = load_windows(root, [sid], context_len=5, horizon_s=3.0)
    assert mine.label.sum() > 0
    np.testing.assert_array_equal(mine.label, ref.label)
    np.testing.assert_array_equal(mine.context_mask, ref.context_mask)
    for name, a in mine.arrays().items():
        np.testing.assert_array_equal(a, ref.arrays()[name], err_msg=name)


def test_config_rejects_unknown_strategy_and_update() -> None:
    with pytest.raises(ValueError, match="strategy"):
        CampaignConfig(SCENARIO, strategy="random-walk")
    with pytest.raises(ValueError, match="update"):
        CampaignConfig(SCENARIO, update="warm")
    assert CampaignConfig(SCENARIO).update == "replay"
    assert CampaignConfig(SCENARIO).train_overrides() == {"epochs": REPLAY_EPOCHS,
                                                          "patience": REPLAY_PATIENCE}
    assert CampaignConfig(SCENARIO, update="finetune").train_overrides() == {
        "epochs": FINETUNE_EPOCHS, "patience": FINETUNE_PATIENCE}
    assert CampaignConfig(SCENARIO, update="retrain").train_overrides() == {}
    with pytest.raises(ValueError, match="committee is of FusionMonitors"):
        CampaignConfig(SCENARIO, strategy="disagreement", family="aem")
    with pytest.raises(ValueError, match="committee must be >= 2"):
        CampaignConfig(SCENARIO, strategy="disagreement", committee=1)


def test_campaign_id_is_stable_and_ignores_the_budget(seeded) -> None:
    root, g0 = seeded
    a = Campaign(root, config(g0, budget_s=100)).campaign_id
    assert a == Campaign(root, config(g0, budget_s=900)).campaign_id
    assert a != Campaign(root, config(g0, seed=1)).campaign_id
    assert a != Campaign(root, config(g0, strategy="uniform")).campaign_id
    assert a != Campaign(root, config(g0, feedback="prior-corrected")).campaign_id
    for blind in ("uniform", "avfuzzer", "no-feedback"):  # they never read the feedback
        ids = {Campaign(root, config(g0, strategy=blind, feedback=f)).campaign_id
               for f in ("raw", "prior-corrected")}
        assert len(ids) == 1, blind
    with pytest.raises(ValueError, match="feedback"):
        config(g0, feedback="calibrated")


def test_prior_corrected_feedback_is_stored_apart_and_undoes_pos_weight(root_copy) -> None:
    from evoeye.evolve.search.feedback import prior_corrected

    root = root_copy("prior")
    g0 = Campaign(root, config(None)).g0
    raw = Campaign(root, config(g0))
    cor = Campaign(root, config(g0, feedback="prior-corrected"))
    raw.start(), cor.start()  # each scores D_init with G_0 and stores it under its own mode
    fb = read_feedback(root)
    by_key: dict[tuple[str, str], dict] = {}
    for v, mode, sid, f in zip(fb.column("monitor_version").to_pylist(),
                               fb.column("feedback_mode").to_pylist(),
                               fb.column("scenario_id").to_pylist(),
                               fb.column("feedback").to_pylist(), strict=True):
        by_key.setdefault((v, mode), {})[sid] = f
    assert set(by_key) == {(g0, "raw"), (g0, "prior-corrected")}
    ids = sorted(by_key[g0, "raw"])
    assert ids == sorted(by_key[g0, "prior-corrected"]) and len(ids) > 0
    monitor = raw.monitor(g0)
    w = load_windows(root, ids, context_len=monitor.context_len, horizon_s=3.0)
    pos_weight = monitor.card["hyperparameters"]["pos_weight"]
    assert pos_weight > 1  # rare unsafe frames: the correction is not a no-op
    p = prior_corrected(monitor.score(w), pos_weight)
    sid = w.scenario_id
    for one in ids[:3]:
        k = sid == one
        assert by_key[g0, "prior-corrected"][one] == pytest.approx(
            np.abs(p[k] - w.label[k]).mean())
        assert by_key[g0, "raw"][one] == pytest.approx(
            np.abs(monitor.score(w)[k] - w.label[k]).mean())


def test_budget_is_never_overspent_and_every_round_is_recorded(root_copy) -> None:
    root = root_copy("budget")
    g0 = Campaign(root, config(None)).g0  # the newest from-scratch monitor of the scenario
    c = Campaign(root, config(g0, strategy="uniform", budget_s=50.0, n_round=2))
    frozen: list[int] = []  # the start-up heap is left out of the rounds' collections
    state = c.run(on_round=lambda row, state: frozen.append(gc.get_freeze_count()))
    assert frozen and min(frozen) > 0 and gc.get_freeze_count() == 0
    assert c.done(state) and state.spent_s <= 50.0
    assert 50.0 - state.spent_s < c.config.max_run_s  # it stopped only when no run fitted
    rows = read_rounds(root, c.campaign_id)
    assert [r.round for r in rows] == list(range(len(rows)))
    assert rows[0].monitor_version == g0 and rows[0].scenario_ids == []
    assert rows[-1].n_records == state.acquired == sum(len(r.scenario_ids) for r in rows)
    # every record carries its feedback under the last monitor
    last = {s: f for v, mode, s, f in snapshot(root, c)["feedback"]
            if (v, mode) == (rows[-1].monitor_version, "raw")}
    assert set(state.records.scenario_id) <= set(last)
    # re-running a finished campaign does nothing
    before = snapshot(root, c)
    Campaign(root, c.config).run()
    assert snapshot(root, c) == before


@pytest.fixture(scope="module")
def clean_runs(seeded, tmp_path_factory: pytest.TempPathFactory):
    """(strategy, family) → snapshot of an uninterrupted 2-round campaign (computed once)."""
    cache: dict[tuple[str, str], dict] = {}

    def get(strategy: str, family: str = "fusion") -> dict:
        if (strategy, family) not in cache:
            root = DataRoot.resolve(tmp_path_factory.mktemp(f"clean-{strategy}") / "data")
            shutil.copytree(seeded[0].path, root.path)
            c = Campaign(root, family_config(seeded[1], family, strategy=strategy))
            c.run(max_rounds=2)
            cache[strategy, family] = snapshot(root, c)
        return cache[strategy, family]
    return get


def family_config(g0: str, family: str, **kw) -> CampaignConfig:
    """A campaign of the family: the FusionMonitor G_0, or AEM-Evo from its own initial AEM."""
    return config(g0, **kw) if family == "fusion" else config(None, family=family, **kw)


@pytest.mark.parametrize("strategy", ["evoeye", "avfuzzer", "boundary", "disagreement"])
def test_killed_mid_round_resumes_to_the_same_records(root_copy, seeded, clean_runs, monkeypatch,
                                                      strategy: str) -> None:
    cfg = config(seeded[1], strategy=strategy)
    expected = clean_runs(strategy)
    assert len(expected["logs"]) == 4 and len(expected["rounds"]) == 3

    root = root_copy("killed")
    real = campaign_mod.simulate_and_keep
    calls = {"n": 0}

    def dies_on_the_fourth_run(spec, where):
        calls["n"] += 1
        if calls["n"] == 4:
            raise KeyboardInterrupt("killed mid-round")
        return real(spec, where)

    monkeypatch.setattr(campaign_mod, "simulate_and_keep", dies_on_the_fourth_run)
    with pytest.raises(KeyboardInterrupt):
        Campaign(root, cfg).run(max_rounds=2)
    assert len(read_rounds(root, Campaign(root, cfg).campaign_id)) == 2  # round 2 cut mid-way
    monkeypatch.setattr(campaign_mod, "simulate_and_keep", real)
    resumed = Campaign(root, cfg)  # round 2's first run is read from its log
    resumed.run(max_rounds=1)
    assert snapshot(root, resumed) == expected


@pytest.mark.parametrize(("family", "strategy"), [("fusion", "evoeye"), ("aem", "evoeye"),
                                                 ("fusion", "disagreement")])
def test_killed_during_training_resumes_to_the_same_records(root_copy, seeded, clean_runs,
                                                            family: str, strategy: str) -> None:
    """(disagreement: killed between the two companions of round 1's committee)"""
    from evoeye.monitor.families import FAMILIES

    cfg = family_config(seeded[1], family, strategy=strategy)
    calls = {"n": 0}

    def dies_in_the_second_update(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 2:
            raise RuntimeError("killed mid-training")
        return FAMILIES[family].train(*args, **kwargs)

    root = root_copy("killed")
    with pytest.raises(RuntimeError, match="mid-training"):
        Campaign(root, cfg, train=dies_in_the_second_update).run(max_rounds=2)
    stored = len(read_rounds(root, Campaign(root, cfg).campaign_id))  # round 0 and any done
    Campaign(root, cfg).run(max_rounds=3 - stored)
    assert snapshot(root, Campaign(root, cfg)) == clean_runs(strategy, family)


def test_hard_set_is_the_missed_unsafe_frames_and_the_safe_frames_of_their_runs(seeded) -> None:
    import pyarrow as pa

    from evoeye.evolve.campaign.assess import hard_set

    root, _ = seeded
    wh = Warehouse(root)
    frames = wh.sql(
        "SELECT l.scenario_id, l.frame, l.label, l.t_s, l.collision_time_s, p.split "
        "FROM frame_labels_h(3.0) l JOIN scenario_splits(0, 0.5, 0.25) p USING (scenario_id) "
        "ORDER BY 1, 2").to_pylist()
    test_runs = sorted({f["scenario_id"] for f in frames if f["split"] == "test"})
    unsafe_runs = sorted({f["scenario_id"] for f in frames
                          if f["split"] == "test" and f["label"] == 1})
    assert len(unsafe_runs) >= 2
    missed = unsafe_runs[1]  # unsafe_runs[0] is caught: all its unsafe frames score high
    score = []
    for f in frames:  # caught: every unsafe frame above 0.5; missed: only its first one
        first_unsafe = f["label"] == 1 and not any(
            g["scenario_id"] == f["scenario_id"] and g["label"] == 1 and g["frame"] < f["frame"]
            for g in frames)
        high = f["label"] == 1 and (f["scenario_id"] != missed or first_unsafe)
        score.append(0.9 if high else 0.1)
    scores = pa.table({
        "monitor_version": ["g0"] * len(frames),
        "scenario_id": [f["scenario_id"] for f in frames],
        "frame": [f["frame"] for f in frames], "score": score,
    })
    other = scores.set_column(0, "monitor_version", pa.array(["other"] * len(frames)))
    hard = hard_set(wh, pa.concat_tables([scores, other.set_column(
        3, "score", pa.array([0.0] * len(frames)))]), monitor_version="g0", threshold=0.5,
        logical_scenario=SCENARIO, splits=SPLITS).to_pylist()
    assert {h["scenario_id"] for h in hard} == {missed}
    eligible = [f for f in frames if f["scenario_id"] == missed and (
        f["collision_time_s"] is None or f["t_s"] < f["collision_time_s"] - 1e-6)]
    n_unsafe = sum(f["label"] for f in eligible)
    assert sum(h["label"] for h in hard) == n_unsafe - 1  # the caught first frame is out
    assert sum(1 - h["label"] for h in hard) == sum(1 - f["label"] for f in eligible)
    assert set(test_runs) >= {h["scenario_id"] for h in hard}


def test_assessor_g0_misses_its_whole_hard_set(seeded) -> None:
    from evoeye.evolve.campaign.assess import Assessor

    root, g0 = seeded
    m = Assessor(root, SCENARIO, g0, splits=SPLITS)(g0)
    assert m.version == g0 and m.hard["recall@0.05"] == 0.0 and m.hard["unsafe"] > 0
    assert m.test["frames"] > m.hard["frames"]


def test_cli_evolve_prints_the_state_and_round_metrics(root_copy, seeded) -> None:
    from typer.testing import CliRunner

    import evoeye.cli.evolve  # noqa: F401  (registers the commands)
    from evoeye.cli.app import app

    root = root_copy("cli")
    args = ["evolve", "--root", str(root.path), "--scenario", SCENARIO, "--strategy", "uniform",
            "--budget-s", "0", "--monitor", seeded[1]]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    assert "campaign evo-uniform-s0-" in res.output and "round 0:" in res.output
    assert "test F1@0.05" in res.output and "budget spent after round 0" in res.output
    assert "evolve: " in res.stderr and "sim s" in res.stderr  # the progress bar
    bad = CliRunner().invoke(app, [*args[:6], "grid"])
    assert bad.exit_code != 0


def test_cli_evolve_without_a_monitor_is_one_line_naming_evoeye_train(root_copy) -> None:
    import shutil

    from typer.testing import CliRunner

    import evoeye.cli.evolve  # noqa: F401  (registers the commands)
    from evoeye.cli.app import app
    from evoeye.cli.errors import ExitCode

    root = root_copy("no-monitor")
    shutil.rmtree(root.monitors)
    res = CliRunner().invoke(app, ["evolve", "--root", str(root.path), "--scenario", SCENARIO,
                                   "--budget-s", "0"])
    assert res.exit_code == ExitCode.USER_ERROR, res.output
    assert "Traceback" not in res.output and len(res.output.strip().splitlines()) == 2
    assert "no monitor trained on" in res.output and "evoeye train --scenario" in res.output
    assert "evoeye monitor train" not in res.output


def test_aem_evo_fine_tunes_the_autoencoder_and_scores_feedback_with_it(root_copy,
                                                                         seeded) -> None:
    from evoeye.evaluation.dataset import load_runs
    from evoeye.evolve.campaign.assess import Assessor
    from evoeye.monitor.families import load_version

    with pytest.raises(ValueError, match="is a fusion monitor, but the campaign evolves the aem"):
        config(seeded[1], family="aem")
    root = root_copy("aem")
    assess = Assessor(root, SCENARIO, seeded[1], splits=SPLITS)  # the FusionMonitor's Hard Set
    cfg = config(None, family="aem", strategy="uniform")
    c = Campaign(root, cfg, assess=assess)
    assert c.campaign_id.startswith("evo-aem-uniform-s0-")
    g0 = c.g0
    assert g0.startswith("aem-") and Campaign(root, cfg).g0 == g0  # found again, not retrained
    c.run(max_rounds=1)
    rows = read_rounds(root, c.campaign_id)
    assert [r.round for r in rows] == [0, 1] and rows[0].monitor_version == g0
    g1 = load_version(root, rows[1].monitor_version)
    assert g1.version != g0 and g1.card["parent"] == g0
    np.testing.assert_array_equal(g1.mean, load_version(root, g0).mean)  # parent's
    # thresholds calibrated on the (eligible: pre-collision) safe frames of the validation split
    val = load_runs(root, SCENARIO, c.val_runs, "val", horizon_s=3.0)
    safe = val.windows.label == 0
    assert (g1.score(val.windows)[safe] > g1.thresholds.at(0.05)).mean() <= 0.05
    # every record's feedback under G_1 is the mean |AEM risk − y| of its frames
    fb = {s: f for v, mode, s, f in snapshot(root, c)["feedback"]
          if (v, mode) == (g1.version, "raw")}
    ids = sorted(fb)[:3]
    w = load_windows(root, ids, context_len=5, horizon_s=3.0)
    risk = g1.score(w)
    for one in ids:
        k = w.scenario_id == one
        assert fb[one] == pytest.approx(np.abs(risk[k] - w.label[k]).mean())
    hard = rows[1].metrics.hard
    assert hard["frames"] == assess(seeded[1]).hard["frames"] > 0


# -- the replay update: each round trains on its runs and a seeded sample of as many earlier --

def capture_training(root, cfg, log: list[list[str]]) -> Campaign:
    """A campaign whose monitor updates are real, with the runs each one trained on logged."""
    def train(*args, train_runs, **kwargs) -> str:
        log.append(list(train_runs))
        return FAMILIES["fusion"].train(*args, train_runs=train_runs, **kwargs)
    return Campaign(root, cfg, train=train)


def test_replay_trains_on_the_rounds_runs_and_as_many_earlier_ones(root_copy, seeded) -> None:
    root = root_copy("replay")
    cfg = config(seeded[1], strategy="uniform", n_round=3)
    trained: list[list[str]] = []
    c = capture_training(root, cfg, trained)
    state = c.run(max_rounds=2)
    initial = set(c.initial["scenario_id"])
    assert len(trained) == 2 and len(initial) > 3
    earlier = set(initial)
    for row, ids in zip(state.rounds[1:], trained, strict=True):
        new = [s for s, ok in zip(state.records.scenario_id, state.ok, strict=True)
               if ok and s in row.scenario_ids]
        assert len(new) == 3 and ids[-3:] == new  # the round's own runs, in order, last
        replayed = ids[:-3]
        assert len(replayed) == 3 and len(set(replayed)) == 3 and set(replayed) <= earlier
        collided = dict(zip(state.records.scenario_id, state.records.collided, strict=True))
        assert any(collided[s] for s in ids)  # both classes to learn from
        earlier |= set(row.scenario_ids)

    again: list[list[str]] = []  # the same campaign elsewhere draws the same samples
    capture_training(root_copy("replay-again"), cfg, again).run(max_rounds=2)
    assert again == trained


def test_finetune_trains_on_every_record(root_copy, seeded) -> None:
    trained: list[list[str]] = []
    c = capture_training(root_copy("finetune"), config(seeded[1], strategy="uniform",
                                                       update="finetune"), trained)
    state = c.run(max_rounds=1)
    ok = [s for s, good in zip(state.records.scenario_id, state.ok, strict=True) if good]
    assert trained == [ok] and len(ok) == len(c.initial["scenario_id"]) + 2


def test_a_round_without_an_ok_run_keeps_its_monitor(root_copy, seeded) -> None:
    c = Campaign(root_copy("failed"), config(seeded[1], strategy="uniform"))
    state = c.start()
    c.acquire(state)
    state.ok[:] = np.arange(len(state.ok)) < len(c.initial["scenario_id"])  # the round failed
    assert state.training_runs(c.config.update, c.config.seed) == []
    assert c.update_monitor(state) == (state.monitor, 0.0)


def test_disagreement_campaign_keeps_a_committee_and_each_runs_spread(root_copy, seeded) -> None:
    """K = 3: two companions per round, found again by later campaigns for round 0, and every
    record's disagreement is the spread of the committee's scores on its warehouse windows."""
    from evoeye.evolve.search.feedback import scenario_disagreement

    root = root_copy("committee")
    c = Campaign(root, config(seeded[1], strategy="disagreement", committee=3))
    state = c.run(max_rounds=2)
    committee = read_committee(root, c.campaign_id)
    assert sorted(committee) == [0, 1, 2] and all(len(v) == 2 for v in committee.values())
    assert len({*committee[0], *committee[1], *committee[2], *(r.monitor_version
                                                              for r in state.rounds)}) == 9
    ok = state.records.scenario_id[state.ok]
    w = load_windows(root, list(ok), context_len=5, horizon_s=3.0)
    members = [state.monitor, *committee[2]]
    expected = scenario_disagreement(np.stack([c.monitor(v).score(w) for v in members]),
                                     w.scenario_id)
    np.testing.assert_allclose(state.records.disagreement[state.ok],
                               expected.aligned(ok), rtol=1e-6)
    assert np.isfinite(state.records.disagreement[state.ok]).all()
    # another campaign of the same G_0 and D_init shares round 0's companions
    other = Campaign(root, config(seeded[1], strategy="disagreement", committee=3, seed=1))
    assert other.committee.companions(0) == committee[0]
    # the committee's size is part of a disagreement campaign's id, of no other
    assert Campaign(root, config(seeded[1], strategy="disagreement", committee=4)).campaign_id \
        != c.campaign_id
    assert Campaign(root, config(seeded[1], committee=4)).campaign_id \
        == Campaign(root, config(seeded[1])).campaign_id
