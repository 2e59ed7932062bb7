"""FusionMonitor.score encodes each frame once: the same risks as scoring every window whole."""

from __future__ import annotations

import numpy as np

from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.registry import load_monitor
from evoeye.store import load_windows


def test_score_gives_each_windows_own_risk_in_any_order(tiny, trained) -> None:
    monitor = load_monitor(tiny.root, trained)
    windows = load_windows(tiny.root, context_len=5, horizon_s=tiny.horizon_s)
    order = np.random.default_rng(0).permutation(len(windows))[: len(windows) // 2]
    part = windows.subset(order)  # shuffled: windows of one frame far apart, frames unshared
    assert (~part.context_mask).any()  # run starts (padded slots) are among them
    whole = monitor.score_batch(part.batch())  # every window encoded on its own
    shared = monitor.score(part)
    np.testing.assert_allclose(shared, whole, rtol=0, atol=1e-5)
    assert whole.std() > 0.05  # varied risks, not a constant
    eager = FusionMonitor(monitor.net, "eager", monitor.thresholds, trace=False)
    np.testing.assert_allclose(eager.score(part), whole, rtol=0, atol=1e-5)
