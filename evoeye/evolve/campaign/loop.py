"""An evolution campaign: Algorithm 1 as a resumable loop of acquisition rounds.

Round r+1 starts from the monitor G_r and the records D_r (D_init, then every run acquired so
far, each with its feedback under G_r). It proposes one scenario at a time, simulates it, scores
the new run with G_r (converted from the Episode just logged, not read back) and adds it to D_r,
until N_round runs or the budget is spent (proposals that wait on no outcome — `propose_ahead`:
Uniform's, Sobol's, the rest of a batched strategy's batch — are simulated together by the
lockstep engine, then scored and added in order: the same runs, records and logs); then it
ingests the round's runs (as converted for scoring: one conversion per log), updates the
monitor on D_r, refreshes the feedback of every record with G_{r+1} and stores the round. The
campaign stops when no run fits in the budget left.

Monitor update (Algorithm 1, line 12: Train(G_r, D_r)) as `CampaignConfig.update` says: from
scratch on D_r by default, or G_r fine-tuned (the option's help and docs/evolution.md say how
each mode trains and what it costs); a round with no new run to learn from keeps G_r.

State and resume. Everything a campaign knows is in the data root: run logs under
`runs/<scenario>/<campaign id>/`, the feedback table (f_r per run and monitor version) and the
campaign_rounds table (per round: G_r and the runs acquired, in order). `start()` rebuilds D_r
(outcomes from the warehouse, no log read again) and the strategy (`replay`) from the last
stored round; a round interrupted anywhere (mid-run, mid-round, mid-training) is re-done from
its start — its proposals are deterministic (the strategy's, and run seed k for proposal k, both
from the campaign's own seed streams, `evoeye.seeds`), logs already on disk are read instead of
simulated, so no run is lost, duplicated or charged twice. A campaign writes only its own keys
(its batch's partition, rounds, monitor versions' feedback: `evoeye.store.lock`), so campaigns
run side by side (`experiment.py`). A run starts only if the budget left is at least the longest
run (`max_run_s`): no budget is overspent. A proposal whose run the root already holds (in any
batch, or among D_r) gets its run seed redrawn (`state.fresh_spec`; the round's `state.redrawn`
names them), so every run a campaign acquires is new and its batch in the warehouse holds as
many runs as it counts records.

A strategy that reads the records' disagreement (`disagreement`) has a committee
(`committee.py`): K − 1 companions updated beside G_r, whose spread of scores is stored per run.

Deviation from Algorithm 1: a last round cut short by the budget still updates G on its paid runs.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from functools import cached_property
from pathlib import Path

import numpy as np

from evoeye.atomic import remove_stale_temps
from evoeye.batch import simulate_and_keep_all
from evoeye.evolve.campaign.committee import Committee
from evoeye.evolve.campaign.config import CampaignConfig, campaign_id
from evoeye.evolve.campaign.guard import CampaignCancelled, campaign_lease
from evoeye.evolve.campaign.phases import PhaseClock
from evoeye.evolve.campaign.scoring import fresh_run_feedback
from evoeye.evolve.campaign.state import (
    CampaignState,
    acquired_runs,
    fresh_spec,
    held_runs,
    initial_profile,
    read_initial,
    records_of,
    run_outcome,
)
from evoeye.evolve.campaign.stored import StoredFeedback
from evoeye.evolve.search.protocol import propose_ahead
from evoeye.evolve.search.registry import (
    FEEDBACK_BLIND,
    READS_DISAGREEMENT,
    make_strategy,
    strategy_options,
)
from evoeye.heap import frozen_heap
from evoeye.monitor.families import (
    DEFAULT_FAMILY,
    FAMILIES,
    SavedMonitor,
    initial_monitor,
    load_calibrated,
)
from evoeye.monitor.threads import intra_op_threads
from evoeye.paths import DataRoot
from evoeye.scenarios import get_scenario
from evoeye.seeds import search_seed
from evoeye.store import RunFilter
from evoeye.store.connections import shared_connections
from evoeye.store.feedback import (
    RoundMetrics,
    RoundRow,
    read_rounds,
)
from evoeye.store.feedback import write_round as store_round
from evoeye.store.ingest import IngestReport, ingest_batch, refresh_catalog
from evoeye.store.log_windows import LoggedRun
from evoeye.store.windows import cached_parts

Trainer = Callable[..., str]  # train_monitor's signature
Assessor = Callable[[str], RoundMetrics]  # monitor version → metrics, stored with the round


class Campaign(StoredFeedback):
    """One campaign over a data root: `start()` (or resume), then `run_round` until `done`."""

    def __init__(self, root: DataRoot, config: CampaignConfig, *,
                 train: Trainer | None = None, assess: Assessor | None = None,
                 initial: dict[str, np.ndarray] | None = None) -> None:
        self.root = root
        self.config = config
        if initial is not None:  # D_init already read, e.g. for another campaign (`campaigns_of`)
            self.__dict__["initial"] = initial
        self.space = get_scenario(config.scenario)
        self.family = FAMILIES[config.family]
        self._train = train or self.family.train
        self._recipe = {"recipe": config.recipe} if self.family.recipes else {}  # its trainings'
        self.assess = assess  # may be set after construction (e.g. from the campaign's ids)
        self._monitors: dict[str, object] = {}
        self.should_stop: Callable[[], bool] | None = None  # asked before each run and update
        self.clock = PhaseClock()  # wall seconds per phase of this object's calls

    # -- identity and initial data -------------------------------------------------------------
    @cached_property
    def initial(self) -> dict[str, np.ndarray]:
        """D_init: the train split of the scenario's round-0 runs, by scenario id."""
        return read_initial(self.root, self.config.scenario, self.config.splits)

    @cached_property
    def g0(self) -> str:
        cfg = self.config
        if cfg.monitor:
            return cfg.monitor
        return self.family.initial(self.root, cfg.scenario,
                                   train_runs=list(self.initial["scenario_id"]),
                                   val_runs=self.val_runs, horizon_s=cfg.horizon_s,
                                   **self._recipe)

    @cached_property
    def reference(self) -> str:
        """The FusionMonitor G_0 whose Hard Set judges this campaign (G_0 itself, or for another
        family, e.g. AEM-Evo, the configured / newest from-scratch FusionMonitor of the scenario).
        """
        if self.config.family == DEFAULT_FAMILY:
            return self.g0
        return self.config.reference or initial_monitor(self.root, self.config.scenario)

    @property
    def val_runs(self) -> RunFilter:
        """The fixed validation split every G_r is early-stopped and calibrated on."""
        return RunFilter(logical_scenario=self.config.scenario, split="val",
                         splits=self.config.splits)

    @cached_property
    def campaign_id(self) -> str:
        """`evo-[aem-]<strategy>-s<seed>-<hash>` (`config.campaign_id`): same inputs, same id."""
        return campaign_id(self.config, self.g0, self.initial["scenario_id"],
                           feedback_blind=self.config.strategy in FEEDBACK_BLIND,
                           committee=self.committee is not None)

    @cached_property
    def committee(self) -> Committee | None:
        """The monitors whose disagreement the strategy reads (None if it reads none)."""
        return Committee(self) if self.config.strategy in READS_DISAGREEMENT else None

    def log_path(self, scenario_id: str) -> Path:
        return self.root.run_log(self.config.scenario, self.campaign_id, scenario_id)

    def monitor(self, version: str) -> SavedMonitor:
        """A version of the campaign's family, with thresholds (loaded once)."""
        if version not in self._monitors:
            self._monitors[version] = load_calibrated(self.root, version)
        return self._monitors[version]

    # -- state -----------------------------------------------------------------------------------
    @intra_op_threads()
    def start(self, new_ids: Sequence[str] = ()) -> CampaignState:
        """The state after the last stored round; round 0 (G_0, D_init scored) is stored first.
        `new_ids`: runs `acquire` added since, by id (the flow's round tasks pass them on), with
        their feedback under G_r. The runs' outcomes come from the warehouse, not their logs."""
        with self.clock("state"):
            return self._start(new_ids)

    @intra_op_threads()
    def store_initial_round(self) -> list[RoundRow]:
        """The stored rounds, round 0 (G_0's feedback on D_init, its assessment) stored first if
        it is not yet."""
        rounds = read_rounds(self.root, self.campaign_id)
        if not rounds:
            self._store_feedback(self.g0, self.initial["scenario_id"])
            if self.committee is not None:
                self.committee.store(self.g0, 0, self.initial["scenario_id"])
            row = RoundRow(self.campaign_id, self.config.scenario, self.config.strategy,
                           self.config.seed, 0, self.g0, [], 0, 0.0,
                           metrics=self._metrics(self.g0))
            store_round(self.root, row)
            rounds = read_rounds(self.root, self.campaign_id)
        return rounds

    def _start(self, new_ids: Sequence[str]) -> CampaignState:
        remove_stale_temps(self.root.batch_dir(self.config.scenario, self.campaign_id))
        rounds = self.store_initial_round()
        last = rounds[-1]
        ids = [*(s for r in rounds for s in r.scenario_ids), *new_ids]
        records, ok = records_of(self.initial, acquired_runs(self.root, self.log_path, ids))
        n_init = len(self.initial["scenario_id"])
        records = self.with_stored(records, last.monitor_version)
        cfg = self.config
        strategy = make_strategy(cfg.strategy, self.space, search_seed(cfg.seed, self.campaign_id),
                                 **strategy_options(cfg.strategy, delta=cfg.delta,
                                                    batch=cfg.n_round))
        mine = records.tail(n_init)
        strategy.replay(mine.params, mine.fitness)
        if hasattr(strategy, "log_densities"):  # its proposals' q, recomputed bit for bit
            records = records.with_densities(*strategy.log_densities(records, n_init))
        return CampaignState(self.campaign_id, last.round, last.monitor_version, records,
                             ok, n_init, strategy, rounds)

    def remaining_s(self, state: CampaignState) -> float:
        return self.config.budget_s - state.spent_s

    def done(self, state: CampaignState) -> bool:
        """No run fits in the budget left."""
        return self.remaining_s(state) < self.config.max_run_s

    def fits(self, state: CampaignState) -> int:
        """How many runs surely fit in the budget left, however long each one runs (up to
        `max_run_s`): each of them would also start if they ran one after another."""
        return int(self.remaining_s(state) // self.config.max_run_s)

    def finished(self) -> bool:
        """`done` from the stored rounds alone: a campaign whose last stored round spent its
        budget has nothing to resume, and a worker need not build its state (a state starts
        from the stored rounds, so its spent time is the last round's `simulated_s`)."""
        rounds = read_rounds(self.root, self.campaign_id)
        return bool(rounds) and (self.config.budget_s - rounds[-1].simulated_s
                                 < self.config.max_run_s)

    # -- one round, in the steps a flow runs as tasks ----------------------------------------------
    @intra_op_threads()
    def acquire(self, state: CampaignState) -> list[str]:
        """Lines 5–10, up to N_round times: propose, simulate, score with G_r, add; then ingest
        the new runs (from their scoring's conversion) and store their f_r. Their ids."""
        cfg, monitor = self.config, self.monitor(state.monitor)
        new: list[str] = []
        runs: list[LoggedRun] = []
        members = (None if self.committee is None  # G_r's committee, for the disagreement
                   else [state.monitor, *self.committee.companions(state.round)])
        spread = None if not members else (
            lambda windows: self.committee.disagreement(members, windows))
        held = held_runs(self.root, cfg.scenario, self.campaign_id, state.records)
        state.redrawn = []
        while len(new) < cfg.n_round and not self.done(state):
            self.check_stop()
            with self.clock("simulate"):
                props = propose_ahead(state.strategy, state.records,
                                      min(cfg.n_round - len(new), self.fits(state)))
                specs = []
                for i, prop in enumerate(props):
                    spec = fresh_spec(cfg, self.campaign_id, prop.x, state, held,
                                      ads=initial_profile(self.initial), number=state.acquired + i)
                    held[spec.scenario_id] = self.campaign_id
                    specs.append(spec)
                simulated = simulate_and_keep_all(specs, self.root)
            for prop, spec, (result, episode) in zip(props, specs, simulated, strict=True):
                if result.status == "error":
                    raise RuntimeError(f"run {spec.scenario_id} could not be simulated: "
                                       f"{result.reason}")
                with self.clock("score"):
                    run, fb, d = fresh_run_feedback(monitor, result.path, episode, cfg.horizon_s,
                                                    cfg.feedback, spread)
                outcome = run_outcome(run.metadata)
                state.strategy.tell(prop.x, outcome["fitness"])
                state.records = state.records.append(
                    np.asarray(run.metadata["params"], float), feedback=float(fb),
                    disagreement=float(d), log_q=prop.log_q, log_p=prop.log_p, **outcome)
                state.ok = np.append(state.ok, run.ok)
                new.append(spec.scenario_id)
                runs.append(run)
        if new:  # in the warehouse, with f_r stored, so that a later step can read them by id
            self._ingest(runs)
            added = state.records.tail(state.records.n - len(new))
            self.write_feedback(state.monitor, added.scenario_id, added.feedback)
            if self.committee is not None:
                self.write_feedback(state.monitor, added.scenario_id, added.disagreement,
                                    mode=self.committee.mode)
        return new

    def ingest(self) -> IngestReport:
        """Put the campaign's logs not yet in the warehouse there (`acquire` ingests its runs:
        this finds none unless it was interrupted), and refresh the DuckDB catalog file."""
        report = self._ingest([])
        refresh_catalog(self.root)
        return report

    def _ingest(self, runs: Sequence[LoggedRun]) -> IngestReport:
        with self.clock("ingest"):
            return ingest_batch(self.root, (self.config.scenario, self.campaign_id), runs)

    @intra_op_threads()
    def update_monitor(self, state: CampaignState) -> tuple[str, float]:
        """Line 12: G_{r+1} from D_r (train) and the fixed val split; (version, wall seconds)."""
        ids = state.training_runs(self.config.update, self.config.seed)
        t0 = time.perf_counter()
        with self.clock("train"):
            if self.committee is not None:  # its companions, beside G_{r+1}
                self.committee.update(state, ids)
            if not ids:  # nothing new to learn from (every run of the round failed): G_r stays
                return state.monitor, 0.0
            version = self.train_monitor_version(
                ids, seed=self.config.seed * 1000 + state.round + 1,
                init_from=state.monitor if self.config.update != "retrain" else None,
                state=state)
        return version, time.perf_counter() - t0

    def train_monitor_version(self, ids: list[str], *, seed: int, init_from: str | None,
                              state: CampaignState | None = None) -> str:
        """A version of the family trained on runs `ids` (fine-tuned from `init_from`, or from
        scratch with G_0's network, `MonitorFamily.network_of`) and the fixed val split, as the
        update trains; with `importance_weights`, each run weighted by its p/q in `state`'s
        records."""
        cfg = self.config
        weights = ({"run_weights": state.records.ratio_by_run()}
                   if cfg.importance_weights and state is not None else {})
        network = {} if init_from else self.family.network_of(self.monitor(self.g0))
        return self._train(self.root, cfg.scenario, train_runs=ids, val_runs=self.val_runs,
                           horizon_s=cfg.horizon_s, seed=seed, splits=cfg.splits,
                           init_from=init_from, **network, **self._recipe,
                           **cfg.train_overrides(), **weights)

    @intra_op_threads()
    def finish_round(self, state: CampaignState, new_ids: list[str], version: str,
                     train_s: float) -> RoundRow:
        """Line 13 and the commit: store f_{r+1} of every record, then the round."""
        with self.clock("state"):
            return self._finish_round(state, new_ids, version, train_s)

    def _finish_round(self, state: CampaignState, new_ids: list[str], version: str,
                      train_s: float) -> RoundRow:
        ok_ids = state.records.scenario_id[state.ok]
        self._store_feedback(version, ok_ids)
        if self.committee is not None:
            self.committee.store(version, state.round + 1, ok_ids)
        row = RoundRow(self.campaign_id, self.config.scenario, self.config.strategy,
                       self.config.seed, state.round + 1, version, list(new_ids),
                       state.acquired, state.spent_s, train_s, self._metrics(version))
        store_round(self.root, row)
        state.records = self.with_stored(state.records, version)
        state.round, state.monitor = row.round, version
        state.rounds.append(row)
        return row

    def run_round(self, state: CampaignState) -> RoundRow | None:
        """One whole round (acquire and ingest → update → refresh); None when the budget is
        spent."""
        new_ids = self.acquire(state)
        if not new_ids:
            return None
        self.check_stop()
        version, train_s = self.update_monitor(state)
        return self.finish_round(state, new_ids, version, train_s)

    def run(self, max_rounds: int | None = None,
            on_round: Callable[[RoundRow, CampaignState], None] | None = None) -> CampaignState:
        """Resume, then run rounds until the budget is spent (or `max_rounds` more are done),
        holding the campaign's lease (`guard.py`: CampaignBusyError if another process runs it).
        Each warehouse part is decoded once for all rounds (`cached_parts`), the warehouse's
        DuckDB views are installed once per state of it (`shared_connections`), and the rounds'
        garbage collections skip what was loaded before them (`frozen_heap`)."""
        with campaign_lease(self.root, self.campaign_id), cached_parts(), \
                shared_connections():
            state = self.start()
            done_rounds = 0
            with frozen_heap():
                while not self.done(state) and (max_rounds is None
                                                or done_rounds < max_rounds):
                    row = self.run_round(state)
                    if row is None:
                        break
                    done_rounds += 1
                    if on_round is not None:
                        on_round(row, state)
        refresh_catalog(self.root)  # its views see the tables the campaign added to
        return state

    # -- helpers ---------------------------------------------------------------------------------
    def check_stop(self) -> None:
        if self.should_stop is not None and self.should_stop():
            raise CampaignCancelled(f"campaign {self.campaign_id} stopped on request")

    def _metrics(self, version: str) -> RoundMetrics | None:
        with self.clock("assess"):
            return self.assess(version) if self.assess else None
