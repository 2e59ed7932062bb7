"""An ensemble of FusionMonitors: members trained on the same windows with distinct seeds,
scored by the mean of their risks.

A FusionMonitor trained on a few hundred runs varies a lot with its training seed; the mean of
k members' risks varies less. The ensemble is one monitor: its thresholds are calibrated on the
validation windows from its own (mean) scores by `calibrate_on_validation`, the calibrator
every single monitor gets (`evoeye.monitor.train.fit_windows`); the members' own thresholds are
not used.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evoeye.monitor.calibration import calibrate_on_validation
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.protocol import Thresholds
from evoeye.store.windows import Windows

MAX_MEMBERS = 8
_STREAM = 38  # the seed stream of members 1 … k−1, apart from every other use of the seed


def member_seeds(seed: int, k: int) -> list[int]:
    """The k training seeds of an ensemble whose member 0 is trained with `seed`: `seed`, then
    k − 1 drawn from a SeedSequence of it (the first k of k + 1 members are the k members'
    seeds). ValueError unless 1 <= k <= MAX_MEMBERS."""
    if not 1 <= k <= MAX_MEMBERS:
        raise ValueError(f"an ensemble has 1 to {MAX_MEMBERS} members, got {k}")
    more = np.random.SeedSequence([int(seed), _STREAM]).generate_state(MAX_MEMBERS - 1)
    seeds = [int(seed), *(int(s) for s in more[: k - 1])]
    if len(set(seeds)) != k:  # a 2^-32 chance: say so rather than train a member twice
        raise ValueError(f"member seeds of {seed} collide: {seeds}")
    return seeds


def mean_risk(scores: Sequence[np.ndarray]) -> np.ndarray:
    """(B,) float64 mean of the members' (B,) risks."""
    return np.mean(np.stack([np.asarray(s, np.float64) for s in scores]), axis=0)


class EnsembleMonitor:
    """Members' mean risk behind the Monitor protocol; thresholds calibrated on validation."""

    name = "fusion-ensemble"

    def __init__(self, members: Sequence[FusionMonitor], thresholds: Thresholds,
                 version: str):
        if not members:
            raise ValueError("an ensemble needs at least one member")
        lengths = {m.context_len for m in members}
        if len(lengths) != 1:
            raise ValueError(f"ensemble members take different context lengths {lengths}")
        self.members = list(members)
        self.thresholds = thresholds
        self.version = version

    @classmethod
    def calibrated(cls, members: Sequence[FusionMonitor], val: Windows,
                   version: str) -> EnsembleMonitor:
        """The ensemble of `members`, its thresholds calibrated on its scores of `val`."""
        ensemble = cls(members, Thresholds(), version)
        ensemble.thresholds = calibrate_on_validation(ensemble.score(val), val)
        return ensemble

    @property
    def context_len(self) -> int:
        return self.members[0].context_len

    def member_scores(self, windows: Windows) -> np.ndarray:
        """(k, B) float32 risks of every member."""
        return np.stack([m.score(windows) for m in self.members])

    def score(self, windows: Windows) -> np.ndarray:
        """(B,) the mean of the members' risks."""
        return mean_risk(self.member_scores(windows))

    def __repr__(self) -> str:
        return f"EnsembleMonitor({self.version!r}, k={len(self.members)})"
