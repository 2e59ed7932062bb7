"""The evolution campaign: Algorithm 1 on real (tiny) simulations, its budget, and resume."""

from __future__ import annotations

import gc
import shutil

import numpy as np
import pytest
from campaign_helpers import SCENARIO, SPLITS, config, snapshot

from evoeye.evolve.campaign import loop as campaign_mod
from evoeye.evolve.campaign.config import (
    FINETUNE_EPOCHS,
    FINETUNE_PATIENCE,
    REPLAY_EPOCHS,
    REPLAY_PATIENCE,
    WARM_EPOCHS,
    WARM_PATIENCE,
    CampaignConfig,
)
from evoeye.evolve.campaign.loop import Campaign
from evoeye.monitor.families import FAMILIES
from evoeye.paths import DataRoot
from evoeye.store import Warehouse, load_windows
from evoeye.store.feedback import read_feedback, read_rounds
from evoeye.store.log_windows import read_logged_run


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
        CampaignConfig(SCENARIO, update="lukewarm")
    assert CampaignConfig(SCENARIO).update == "retrain"
    assert CampaignConfig(SCENARIO, update="replay").train_overrides() == {
        "epochs": REPLAY_EPOCHS, "patience": REPLAY_PATIENCE}
    assert CampaignConfig(SCENARIO, update="finetune").train_overrides() == {
        "epochs": FINETUNE_EPOCHS, "patience": FINETUNE_PATIENCE}
    assert CampaignConfig(SCENARIO, update="warm").train_overrides() == {
        "epochs": WARM_EPOCHS, "patience": WARM_PATIENCE}
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
    real = campaign_mod.simulate_and_keep_all
    calls = {"n": 0}

    def dies_on_the_fourth_run(specs, where):  # the runs before it are on disk
        before = calls["n"]
        calls["n"] += len(specs)
        if before < 4 <= calls["n"]:
            real(specs[:3 - before], where)
            raise KeyboardInterrupt("killed mid-round")
        return real(specs, where)

    monkeypatch.setattr(campaign_mod, "simulate_and_keep_all", dies_on_the_fourth_run)
    with pytest.raises(KeyboardInterrupt):
        Campaign(root, cfg).run(max_rounds=2)
    assert len(read_rounds(root, Campaign(root, cfg).campaign_id)) == 2  # round 2 cut mid-way
    monkeypatch.setattr(campaign_mod, "simulate_and_keep_all", real)
    resumed = Campaign(root, cfg)  # round 2's first run is read from its log
    resumed.run(max_rounds=1)
    assert snapshot(root, resumed) == expected


@pytest.mark.parametrize(("family", "strategy"), [("fusion", "evoeye"), ("aem", "evoeye"),
                                                 ("fusion", "disagreement")])
def test_killed_during_training_resumes_to_the_same_records(root_copy, seeded, clean_runs,
                                                            family: str, strategy: str) -> None:
    """(disagreement: killed between the two companions of round 1's committee)"""

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
            "--budget-s", "1", "--monitor", seeded[1]]  # no run fits in 1 s (up to 20 s each)
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    assert "campaign evo-uniform-s0-" in res.output and "round 0:" in res.output
    assert "test F1@0.05" in res.output and "budget spent after round 0" in res.output
    assert "evolve: " in res.stderr and "sim s" in res.stderr  # the progress bar
    bad = CliRunner().invoke(app, [*args[:6], "grid"])
    assert bad.exit_code != 0
    none = CliRunner().invoke(app, [*args[:8], "0", *args[9:]])  # --budget-s 0
    assert none.exit_code == 2 and "--budget-s" in none.output
    assert "leaves no run to simulate" in none.output and "campaign evo-" not in none.output


def test_cli_evolve_without_a_monitor_is_one_line_naming_evoeye_train(root_copy) -> None:
    import shutil

    from typer.testing import CliRunner

    import evoeye.cli.evolve  # noqa: F401  (registers the commands)
    from evoeye.cli.app import app
    from evoeye.cli.errors import ExitCode

    root = root_copy("no-monitor")
    shutil.rmtree(root.monitors)
    res = CliRunner().invoke(app, ["evolve", "--root", str(root.path), "--scenario", SCENARIO,
                                   "--budget-s", "1"])
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
    cfg = config(None, family="aem", strategy="uniform", update="replay")  # the paper's loop
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


def test_ce_is_campaign_trains_with_its_runs_weights_and_a_resume_recomputes_them(
        root_copy, seeded, monkeypatch) -> None:
    # 13 runs are too few for a dimension to pass the screening: let every one adapt
    monkeypatch.setattr("evoeye.evolve.search.cross_entropy.SCREEN_Z", 0.0)
    cfg = config(seeded[1], strategy="ce-is", importance_weights=True, n_round=4)
    seen: list[dict[str, float]] = []

    def train(*args, **kwargs):
        seen.append(kwargs["run_weights"])
        assert kwargs["importance_weights"] is True
        return FAMILIES["fusion"].train(*args, **kwargs)

    root = root_copy("ce-is")
    state = Campaign(root, cfg, train=train).run(max_rounds=3)
    acquired = state.records.tail(state.n_init)
    assert np.isfinite(acquired.log_q).all() and np.isfinite(acquired.log_p).all()
    ratio = dict(zip(state.records.scenario_id, state.records.importance_ratio(), strict=True))
    assert len(seen) == 3 and seen[-1] == ratio  # the last update: every record's p/q
    assert all(ratio[s] == 1.0 for s in state.records.scenario_id[:state.n_init])
    assert (state.records.importance_ratio()[-4:] != 1.0).all()  # round 3 drew from a fit q
    again = Campaign(root, cfg).start()  # rebuilt from the tables and the seed
    np.testing.assert_array_equal(again.records.log_q, state.records.log_q)
