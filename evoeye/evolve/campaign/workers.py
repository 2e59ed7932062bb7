"""Independent campaigns side by side: local processes, or the workers of a Dask cluster.

A campaign runs whole in one worker (`run_campaign`, a plain function of picklable arguments, so
a Prefect task runner can run it too: flows/experiment.py). Campaigns share nothing but the data
root, where each writes only its own keys (its batch's partition, its rounds, its monitor
versions' feedback: `evoeye.store.lock`), so none waits for another and any of them can be
killed and resumed alone. What several campaigns would write alike — G_0's feedback on D_init,
its assessment, an AEM-Evo campaign's initial AEM — is written before they fan out
(`prepare_campaigns`, in the calling process).

Each worker process builds one Test/Hard-Set assessor per scenario on first use and keeps it;
local workers are forked from the caller after it built them, so they start with them.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import dataclass
from importlib import import_module

from evoeye.evolve.campaign.assess import Assessor
from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.campaign.state import redrawn_note
from evoeye.lifeline import pool_context, stop_workers, stoppable, stoppable_worker
from evoeye.paths import DataRoot
from evoeye.store.feedback import RoundMetrics, read_rounds

# a fixed glibc malloc trim threshold (Dask's nannies set one) without an mmap threshold
MALLOC_TRIM, MALLOC_MMAP = "MALLOC_TRIM_THRESHOLD_", "MALLOC_MMAP_THRESHOLD_"


@dataclass(frozen=True)
class CampaignJob:
    """One campaign to run (or resume) to its budget, from a worker."""

    root: str  # the data root's path
    config: CampaignConfig
    label: str  # how progress names it, e.g. "highway-cut-in evoeye seed 0"
    assess: bool = True  # every G_r on the Test Set and the Hard Set


@dataclass(frozen=True)
class CampaignDone:
    """What a worker reports of a campaign it ran."""

    label: str
    campaign_id: str
    rounds: int  # rounds run by this worker (0: it was finished already)
    lines: tuple[str, ...]  # one per round


Brief = Callable[[RoundMetrics | None], str]  # a round's metrics in one line (picklable)
_ASSESSORS: dict[tuple, Assessor] = {}  # this process's, by (root, scenario, G_0, split, H)
_LINES: mp.Queue | None = None  # where a local worker sends its round lines as they come


def assessor(campaign: Campaign) -> Assessor:
    """This process's assessor of the campaign's scenario and reference G_0 (built once)."""
    cfg = campaign.config
    key = (str(campaign.root.path), cfg.scenario, campaign.reference, cfg.splits, cfg.horizon_s)
    if key not in _ASSESSORS:
        _ASSESSORS[key] = Assessor.of(campaign)
    return _ASSESSORS[key]


def _campaign(job: CampaignJob) -> Campaign:
    """The job's campaign, assessed (if asked) by this process's assessor of its scenario."""
    campaign = Campaign(DataRoot.resolve(job.root), job.config)
    if job.assess:
        campaign.assess = assessor(campaign)
    return campaign


def prepare_campaigns(jobs: Sequence[CampaignJob]) -> None:
    """Resolve every campaign's G_0 and store its round 0 (G_0's feedback on D_init and its
    assessment), one campaign after another: what the campaigns would otherwise all write."""
    for job in jobs:
        _campaign(job).store_initial_round()


def no_metrics(metrics: RoundMetrics | None) -> str:
    return ""


def run_campaign(job: CampaignJob, brief: Brief = no_metrics,
                 say: Callable[[str], None] | None = None,
                 should_stop: Callable[[], bool] | None = None) -> CampaignDone:
    """Run (or resume) one campaign to its budget; `say` each round's line as it ends (in a
    local worker, it goes to the process that started the workers); `should_stop`: asked
    before each run and monitor update (`Campaign.should_stop`)."""
    campaign = _campaign(job)
    campaign.should_stop = should_stop
    if campaign.finished():  # a cached re-run: nothing to resume, no state to build
        return CampaignDone(job.label, campaign.campaign_id, 0, ())
    say = say or (_LINES.put if _LINES is not None else None)
    lines: list[str] = []
    if say is not None:  # a resumed campaign's stored rounds, said again: a worker killed
        # between storing a round and sending its line (SIGKILL) would otherwise lose the line
        for row in read_rounds(campaign.root, campaign.campaign_id)[1:]:  # round 0 is G_0's
            say(f"{job.label} round {row.round}: {brief(row.metrics)} | stored before this "
                "worker resumed it")

    def on_round(row, state) -> None:
        note = redrawn_note(state)
        lines.append(f"{job.label} round {row.round}: {brief(row.metrics)}"
                     + (f" | {note}" if note else ""))
        if say is not None:
            say(lines[-1])

    campaign.run(on_round=on_round)
    return CampaignDone(job.label, campaign.campaign_id, len(lines), tuple(lines))


# what a campaign imports on first use (the simulator, the monitor's training, the warehouse's
# writer): a worker that imports them as it starts runs its first campaign without the wait
CAMPAIGN_MODULES = ("evoeye.batch", "evoeye.baselines", "evoeye.evolve.search",
                    "evoeye.monitor.registry", "evoeye.monitor.train", "evoeye.sim.runner",
                    "evoeye.store.ingest")


def dask_setup(worker: object = None) -> None:
    """Dask's preload hook (`dask worker --preload evoeye.evolve.campaign.workers`): import what
    a campaign runs with as the worker starts — about 2–4 s — as a local pool's forked workers
    inherit it from their parent, instead of inside the worker's first campaign."""
    for name in CAMPAIGN_MODULES:
        import_module(name)


def _local_worker(parent: int, lines: mp.Queue) -> None:
    global _LINES
    stoppable_worker(parent)
    _LINES = lines


def worker_malloc() -> tuple[str | None, str | None]:
    return os.environ.get(MALLOC_TRIM), os.environ.get(MALLOC_MMAP)


def malloc_note(envs: dict[str, tuple[str | None, str | None]]) -> str | None:
    """A note if Dask workers (address → their malloc variables) run with a fixed trim
    threshold and no mmap threshold — Dask's default, which turns off glibc's dynamic mmap
    threshold and makes training ≈ 1.5× dearer (docs/evolution.md); None if none does."""
    slow = sorted(w for w, (trim, mmap) in envs.items() if trim is not None and mmap is None)
    if not slow:
        return None
    return (f"note: {len(slow)} of {len(envs)} Dask workers run with "
            f"{MALLOC_TRIM}={envs[slow[0]][0]} and no {MALLOC_MMAP}: training a monitor costs "
            "them ≈ 1.5× the CPU; docs/evolution.md says how to start workers without it")


@contextmanager
def _local_pool(workers: int, say: Callable[[str], None]) -> Iterator[ProcessPoolExecutor]:
    """`workers` local processes relaying round lines to `say`; stopped at once (SIGTERM,
    `evoeye.lifeline`) if the block fails, so no campaign outlives the command."""
    context = pool_context()
    lines: mp.Queue = context.Queue()
    relay = threading.Thread(target=lambda: [say(m) for m in iter(lines.get, None)],
                             daemon=True)
    relay.start()
    try:
        with ProcessPoolExecutor(max_workers=workers, mp_context=context,
                                 initializer=_local_worker,
                                 initargs=(os.getpid(), lines)) as pool:
            try:
                yield pool
            except BaseException:
                stop_workers(pool)
                raise
    finally:
        lines.put(None)
        relay.join()


def run_campaigns(jobs: Sequence[CampaignJob], *, workers: int | None = None,
                  dask_address: str | None = None, brief: Brief = no_metrics,
                  progress: Callable[[str], None] = print) -> list[CampaignDone]:
    """Prepare, then run every campaign: one after another in this process (`workers` 1, no
    address), over `workers` local processes (default: one per CPU), or over the workers of
    the Dask scheduler at `dask_address` (give them one thread each: a campaign per worker at a
    time; `cluster.py`: preflight, loss, timeout). In job order; if one fails, the others
    are stopped (those not started yet are not started) and the failure is raised."""
    if workers is not None and workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    workers = min(workers or os.cpu_count() or 1, max(len(jobs), 1))
    lock = threading.Lock()  # the workers' lines arrive on a thread of their own

    def say(line: str) -> None:
        with lock:
            progress(line)

    if dask_address:
        from evoeye.evolve.campaign.cluster import run_on_dask

        references = sorted({Campaign(DataRoot.resolve(j.root), j.config).reference
                             for j in jobs})
        return run_on_dask(jobs, dask_address, brief, say, references,
                           prepare=lambda: prepare_campaigns(jobs), run=run_campaign)
    prepare_campaigns(jobs)
    if workers == 1:
        return [run_campaign(job, brief, progress) for job in jobs]
    done: dict[int, CampaignDone] = {}
    with _local_pool(workers, say) as pool:
        futures = {pool.submit(stoppable, run_campaign, job, brief): i
                   for i, job in enumerate(jobs)}
        for future in as_completed(futures):
            done[futures[future]] = result = future.result()
            say(f"{result.label}: campaign {result.campaign_id}, {result.rounds} round(s) "
                "run, budget spent")
    return [done[i] for i in range(len(jobs))]
