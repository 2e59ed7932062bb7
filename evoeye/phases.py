"""Where time goes: wall and CPU seconds per named phase of a piece of work, for profiling.

A campaign's rounds (`evoeye.evolve.campaign.phases`) and a monitor's training
(`evoeye.monitor.fit`) count their phases with it.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager


class PhaseClock:
    """Wall and CPU seconds per phase of `phases`; a phase entered inside another pauses the
    outer one, so every second is counted once. `cpu` is the CPU clock: the process's, or the
    thread's (`time.thread_time`) for work that shares its process with other threads."""

    def __init__(self, phases: Sequence[str],
                 cpu: Callable[[], float] = time.process_time) -> None:
        self.seconds = dict.fromkeys(phases, 0.0)
        self.cpu_seconds = dict.fromkeys(phases, 0.0)
        self._cpu = cpu
        self._stack: list[str] = []
        self._since = (0.0, 0.0)

    @contextmanager
    def __call__(self, phase: str) -> Iterator[None]:
        if phase not in self.seconds:
            raise ValueError(f"unknown phase {phase!r}; known: {tuple(self.seconds)}")
        self._switch(phase)
        try:
            yield
        finally:
            self._switch(None)

    def _switch(self, entering: str | None) -> None:
        now = (time.perf_counter(), self._cpu())
        if self._stack:
            self.seconds[self._stack[-1]] += now[0] - self._since[0]
            self.cpu_seconds[self._stack[-1]] += now[1] - self._since[1]
        if entering is None:
            self._stack.pop()
        else:
            self._stack.append(entering)
        self._since = now

    def rounded(self, digits: int = 2) -> dict[str, dict[str, float]]:
        """{phase: {"wall_s", "cpu_s"}}, rounded, as a card or a report records them."""
        return {p: {"wall_s": round(self.seconds[p], digits),
                    "cpu_s": round(self.cpu_seconds[p], digits)} for p in self.seconds}
