"""What a campaign keeps of its monitors' judgements: each run's feedback f under a monitor
version, stored in the warehouse's feedback table and read back into the records.

`Campaign` (`loop.py`) inherits these; they need its `root`, `config`, `clock`, `monitor(version)`
and `committee` (the companions whose disagreement `disagreement` reads, or None).
"""

from __future__ import annotations

import numpy as np

from evoeye.evolve.campaign.scoring import warehouse_feedback
from evoeye.evolve.search.records import Records
from evoeye.store.feedback import FeedbackRows, feedback_of, write_feedback


class StoredFeedback:
    """The feedback a campaign stores and reads (module doc)."""

    def stored_feedback(self, version: str) -> dict[str, float]:
        """scenario_id → f stored under `version` in this campaign's feedback mode (G_0's is
        shared by every campaign of the mode)."""
        return feedback_of(self.root, version, self.config.feedback)

    def _store_feedback(self, version: str, scenario_ids) -> None:
        """Score ingested runs with `version` and store f (runs already stored are skipped)."""
        have = self.stored_feedback(version)
        todo = [str(s) for s in scenario_ids if s not in have]
        if not todo:
            return
        with self.clock("refresh"):
            fb = warehouse_feedback(self.root, self.monitor(version), todo,
                                    self.config.horizon_s, self.config.feedback)
        self.write_feedback(version, fb.scenario_id, fb.feedback, fb.n_contexts)

    def write_feedback(self, version: str, ids, values, n_contexts=None,
                       mode: str | None = None) -> None:
        """Store per-run values (the finite ones) under `version` in `mode` (default: ours)."""
        write_feedback(self.root, FeedbackRows.finite(self.config.scenario, version,
                                                      mode or self.config.feedback, ids, values,
                                                      n_contexts))

    def with_stored(self, records: Records, version: str) -> Records:
        """`records` with the feedback (and the committee's disagreement) stored under G_r =
        `version`; NaN where none is."""
        def aligned(stored: dict[str, float]) -> np.ndarray:
            return np.array([stored.get(s, np.nan) for s in records.scenario_id], dtype=float)

        records = records.with_feedback(aligned(self.stored_feedback(version)))
        return records if self.committee is None else records.with_disagreement(
            aligned(self.committee.stored(version)))
