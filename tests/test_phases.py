"""The phase clock: every second counted once, in the innermost phase."""

from __future__ import annotations

import pytest

from evoeye import phases
from evoeye.evolve.campaign.phases import PHASES
from evoeye.evolve.campaign.phases import PhaseClock as CampaignClock
from evoeye.phases import PhaseClock


class FakeTime:
    """perf_counter advances by 1 s per reading, the CPU clock reads half of it."""

    def __init__(self) -> None:
        self.n = 0

    def perf_counter(self) -> float:
        self.n += 1
        return float(self.n)

    def cpu(self) -> float:
        return self.n / 2


def test_a_nested_phase_pauses_the_outer_one(monkeypatch: pytest.MonkeyPatch) -> None:
    fake = FakeTime()
    monkeypatch.setattr(phases.time, "perf_counter", fake.perf_counter)
    clock = PhaseClock(("state", "refresh", "assess", "train"), fake.cpu)
    with clock("state"):  # reading 1
        with clock("refresh"):  # reading 2: state got 1 s
            pass  # reading 3: refresh got 1 s
        with clock("assess"):  # reading 4: state got 1 s more
            pass  # reading 5: assess got 1 s
    # reading 6: state got its last 1 s
    assert clock.seconds["state"] == 3 and clock.seconds["refresh"] == 1
    assert clock.seconds["assess"] == 1 and clock.seconds["train"] == 0
    assert clock.cpu_seconds["state"] == 1.5 and clock.cpu_seconds["assess"] == 0.5
    assert clock.rounded()["state"] == {"wall_s": 3.0, "cpu_s": 1.5}


def test_an_unknown_phase_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown phase 'lunch'"), CampaignClock()("lunch"):
        pass
    assert tuple(CampaignClock().seconds) == PHASES
