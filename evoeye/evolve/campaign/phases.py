"""Where a campaign's time goes: wall and CPU seconds per phase of its rounds, for profiling.

    simulate  propose and simulate the round's runs, writing their logs
    score     convert each new run as the warehouse does (from its Episode in memory, or the
              log a resumed round finds on disk) and score it with G_r
    ingest    put the round's runs into the warehouse
    train     the monitor update G_r → G_{r+1}
    refresh   every record's feedback under G_{r+1}
    assess    G_{r+1} on the Test Set and the Hard Set
    state     the campaign's state: rebuilding it, storing feedback and rounds
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager

PHASES = ("simulate", "score", "ingest", "train", "refresh", "assess", "state")


class PhaseClock:
    """Wall and CPU seconds (of this process) per phase; a phase entered inside another pauses
    the outer one, so every second is counted once."""

    def __init__(self) -> None:
        self.seconds = dict.fromkeys(PHASES, 0.0)
        self.cpu_seconds = dict.fromkeys(PHASES, 0.0)
        self._stack: list[str] = []
        self._since = (0.0, 0.0)

    @contextmanager
    def __call__(self, phase: str) -> Iterator[None]:
        if phase not in self.seconds:
            raise ValueError(f"unknown phase {phase!r}; known: {PHASES}")
        self._switch(phase)
        try:
            yield
        finally:
            self._switch(None)

    def _switch(self, entering: str | None) -> None:
        now = (time.perf_counter(), time.process_time())
        if self._stack:
            self.seconds[self._stack[-1]] += now[0] - self._since[0]
            self.cpu_seconds[self._stack[-1]] += now[1] - self._since[1]
        if entering is None:
            self._stack.pop()
        else:
            self._stack.append(entering)
        self._since = now
