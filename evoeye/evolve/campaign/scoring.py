"""Feedback f_r(x) of runs under a monitor: from a fresh run log, or from the warehouse.

A new record is scored straight from its MCAP log (`evoeye.store.log_windows`, the warehouse's
own conversion), so it needs no ingest and gives the scores its warehouse windows would get: no
frame at or after the run's collision enters its feedback. Runs already ingested (the refresh
after a monitor update) are scored from the warehouse.
"""

from __future__ import annotations

import numpy as np

from evoeye.evolve.campaign.config import FEEDBACK_MODES
from evoeye.evolve.search.feedback import ScenarioFeedback, prior_corrected, scenario_feedback
from evoeye.paths import DataRoot
from evoeye.sim.episode import Episode
from evoeye.store.log_windows import LoggedRun, episode_run, read_logged_run
from evoeye.store.windows import Windows, load_windows


def windows_feedback(monitor, windows: Windows, mode: str = "raw") -> ScenarioFeedback:
    """f_r per run of `windows` under `monitor` (anything with `.score(windows)`); with
    "prior-corrected", ŷ first undoes the monitor's training pos_weight (card, default 1)."""
    return scenario_feedback(mode_scores(monitor, windows, mode), windows.label,
                             windows.scenario_id)


def mode_scores(monitor, windows: Windows, mode: str = "raw") -> np.ndarray:
    """ŷ (B,) of every context of `windows` under `monitor`, as the feedback `mode` takes it."""
    if mode not in FEEDBACK_MODES:
        raise ValueError(f"feedback mode must be one of {FEEDBACK_MODES}, got {mode!r}")
    scores = monitor.score(windows)
    if mode == "prior-corrected":
        card = getattr(monitor, "card", None) or {}
        scores = prior_corrected(scores, card.get("hyperparameters", {}).get("pos_weight") or 1.0)
    return scores


def warehouse_feedback(root: DataRoot, monitor, scenario_ids, horizon_s: float,
                       mode: str = "raw") -> ScenarioFeedback:
    """f_r of ingested runs, scored from their warehouse windows (the refresh of line 13)."""
    windows = load_windows(root, list(scenario_ids), context_len=monitor.context_len,
                           horizon_s=horizon_s)
    return windows_feedback(monitor, windows, mode)


def fresh_run_feedback(monitor, path, episode: Episode | None, horizon_s: float, mode: str,
                       disagreement=None) -> tuple[LoggedRun, float, float]:
    """A just-simulated run converted (from its Episode, or from its log when a resumed round
    finds it on disk) and its f_r under `monitor` and, with `disagreement` (windows → its
    ScenarioFeedback), the committee's spread; NaN for a run without windows."""
    run = (read_logged_run(path, monitor.context_len, horizon_s) if episode is None
           else episode_run(episode, path, monitor.context_len, horizon_s))
    if not (run.ok and run.windows is not None):
        return run, np.nan, np.nan
    fb = windows_feedback(monitor, run.windows, mode).feedback[0]
    d = np.nan if disagreement is None else disagreement(run.windows).feedback[0]
    return run, float(fb), float(d)
