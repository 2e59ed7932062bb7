"""Campaigns on a Dask cluster without surprises: preflight, live lines, loss, stop, timeout.

* **Preflight**, before any campaign starts: at least one worker within `NO_WORKERS_TIMEOUT_S`,
  then every worker answers, within `PREFLIGHT_TIMEOUT_S`, that it runs the client's evoeye
  version, sees the data root at the client's path (its `warehouse/` and every G_0 the plan
  needs under `monitors/`) and may write there. The first that does not is named in one line.
* **Live lines**: a worker publishes each round's line on a Dask event topic of the experiment
  as the round ends. A campaign that moves to another worker says its stored rounds' lines
  again as it resumes (`workers.run_campaign`): a line still in flight when its worker was
  killed is otherwise lost.
* **Loss**: a worker that leaves while running campaigns is reported with the campaigns that
  move; a campaign resumes from its last stored round, so its records are those of a run never
  interrupted. With no worker left for `NO_WORKERS_TIMEOUT_S`, the experiment fails.
* **Stop**: if a campaign fails, a Dask `Event` of the experiment is set; every running campaign
  sees it before its next run or monitor update and stops (`guard.CampaignCancelled`); the
  experiment waits for them (up to `STOP_TIMEOUT_S`) before it reports the failure.
"""

from __future__ import annotations

import os
import socket
import time
import uuid
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from concurrent.futures import TimeoutError as FuturesTimeout
from typing import TYPE_CHECKING, Any

from evoeye import __version__
from evoeye.evolve.campaign.guard import CampaignCancelled
from evoeye.paths import DataRoot

if TYPE_CHECKING:
    from distributed import Client

    from evoeye.evolve.campaign.workers import CampaignDone, CampaignJob

NO_WORKERS_TIMEOUT_S = 60.0  # no worker at start, or none left, for this long: fail
PREFLIGHT_TIMEOUT_S = 25.0  # every worker's answer to the preflight
STOP_TIMEOUT_S = 120.0  # how long a failed experiment waits for its campaigns to stop
POLL_S = 1.0  # how often the client looks at the cluster while campaigns run


class ClusterError(RuntimeError):
    """The cluster cannot run the campaigns (a worker's view, no worker, a failed campaign)."""


def worker_view(root: str, monitors: Sequence[str], version: str) -> tuple[str, str]:
    """(this host, what it lacks to run the campaigns; '' if nothing): run on every worker."""
    host = socket.gethostname()
    if __version__ != version:
        return host, f"runs evoeye {__version__}, the client {version}"
    data = DataRoot.resolve(root)
    for folder in (data.path, data.warehouse, *(data.monitors / m for m in monitors)):
        if not folder.is_dir() or not os.access(folder, os.R_OK | os.X_OK):
            return host, f"cannot see {folder}"
    if not os.access(data.path, os.W_OK):
        return host, f"cannot write to {data.path}"
    return host, ""


def preflight(client: Client, address: str, root: str, monitors: Sequence[str]) -> list[str]:
    """Wait for a worker, check every worker's view (module doc); the workers' addresses, or
    ClusterError naming the first worker that lacks something."""
    try:
        client.wait_for_workers(1, timeout=NO_WORKERS_TIMEOUT_S)
    except TimeoutError:
        raise ClusterError(f"no Dask worker joined the scheduler at {address} within "
                           f"{NO_WORKERS_TIMEOUT_S:.0f} s: start workers first "
                           "(docs/distributed.md)") from None
    with ThreadPoolExecutor(1) as ask:
        answer = ask.submit(client.run, worker_view, root, list(monitors), __version__,
                            on_error="return")
        try:
            views = answer.result(timeout=PREFLIGHT_TIMEOUT_S)
        except FuturesTimeout:
            raise ClusterError(f"the Dask workers at {address} did not answer the preflight "
                               f"within {PREFLIGHT_TIMEOUT_S:.0f} s") from None
    bad = {w: (("?", f"failed the preflight: {v}") if isinstance(v, BaseException) else v)
           for w, v in views.items() if isinstance(v, BaseException) or v[1]}
    if bad:
        worker = sorted(bad)[0]
        host, lack = bad[worker]
        more = f" (and {len(bad) - 1} other worker(s))" if len(bad) > 1 else ""
        raise ClusterError(f"Dask worker {worker} on {host} {lack}{more}: every worker must "
                           "run the same evoeye and see the data root at the same path "
                           "(docs/distributed.md)")
    return sorted(views)


def check_cluster(address: str, root: str, monitors: Sequence[str]) -> list[str]:
    """`preflight` with a client of its own (for a caller whose task runner connects later);
    the workers' addresses."""
    from distributed import Client

    with Client(address) as client:
        return preflight(client, address, root, monitors)


def loopback_api_note(api_url: str | None) -> str | None:
    """A note if the Prefect API the workers are handed is this host's loopback address, which
    workers on other hosts cannot reach; None otherwise."""
    from urllib.parse import urlparse

    host = urlparse(api_url or "").hostname or ""
    if host not in ("127.0.0.1", "localhost", "::1"):
        return None
    return (f"note: the Prefect API at {api_url} is this host's loopback address: Dask workers "
            "on other hosts cannot reach it; start `prefect server start --host 0.0.0.0` and "
            "set PREFECT_API_URL on every host (docs/distributed.md)")


def dask_say(topic: str) -> Callable[[str], None]:
    """A worker's `say`: publish the line on the experiment's topic (the client prints it)."""
    from distributed import get_worker

    return lambda line: get_worker().log_event(topic, line)


def dask_should_stop(event: str) -> Callable[[], bool]:
    """A worker's `Campaign.should_stop`: whether the experiment's stop event is set."""
    from distributed import Event, get_client

    flag = Event(event, client=get_client())
    return flag.is_set


def _labels(client: Client, keys: dict[str, str]) -> dict[str, list[str]]:
    """worker → labels of the campaigns it is running."""
    return {w: sorted(keys[str(k)] for k in ks if str(k) in keys)
            for w, ks in client.processing().items()}


def run_on_dask(jobs: Sequence[CampaignJob], address: str, brief: Callable,
                say: Callable[[str], None], monitors: Sequence[str], *,
                prepare: Callable[[], None], run: Callable[..., CampaignDone]
                ) -> list[CampaignDone]:
    """Run every job on the cluster at `address` (module doc): the preflight (`monitors`: the
    versions every worker must see), then `prepare()` here, then `run(job, brief, say=…,
    should_stop=…)` in the workers; their CampaignDone in job order."""
    if not jobs:
        return []
    from distributed import Client, Event, wait

    from evoeye.evolve.campaign.workers import malloc_note, worker_malloc

    token = uuid.uuid4().hex[:12]
    topic, event = f"evoeye-lines-{token}", f"evoeye-stop-{token}"
    with Client(address) as client:
        workers = set(preflight(client, address, jobs[0].root, monitors))
        note = malloc_note(client.run(worker_malloc))
        if note:
            say(note)
        prepare()
        client.subscribe_topic(topic, lambda ev: say(str(ev[1])))
        stop = Event(event, client=client)
        futures = [client.submit(_remote, run, job, brief, topic, event, pure=False,
                                 key=f"campaign-{i}-{token}") for i, job in enumerate(jobs)]
        keys = {f.key: job.label for f, job in zip(futures, jobs, strict=True)}
        running = _labels(client, keys)
        pending, empty_since, done = set(futures), None, {}
        try:
            while pending:
                try:
                    finished, pending = wait(list(pending), timeout=POLL_S,
                                             return_when="FIRST_COMPLETED")
                except TimeoutError:
                    finished = set()
                for f in finished:
                    done[f.key] = result = f.result()
                    say(f"{result.label}: campaign {result.campaign_id}, {result.rounds} "
                        "round(s) run, budget spent")
                now = set(client.scheduler_info()["workers"])
                for gone in sorted(workers - now):
                    moved = running.get(gone, [])
                    say(f"Dask worker {gone} left the cluster"
                        + (f"; its campaign(s) {', '.join(moved)} move to another worker and "
                           "resume from their last stored round: results are unaffected"
                           if moved else ""))
                workers, running = now, _labels(client, keys) if now else running
                empty_since = _check_empty(now, empty_since, address, pending, keys)
        except BaseException:
            stop.set()  # a campaign not started yet stops as it starts (`_remote`)
            _wait_stopped(client, futures, say)
            raise
        finally:
            client.unsubscribe_topic(topic)
    return [done[f.key] for f in futures]


def _check_empty(now: set, since: float | None, address: str, pending: set,
                 keys: dict[str, str]) -> float | None:
    """When the cluster has had no worker since `since` (None: it has some) — or ClusterError
    after NO_WORKERS_TIMEOUT_S of that."""
    if now or not pending:
        return None
    since = since or time.monotonic()
    if time.monotonic() - since > NO_WORKERS_TIMEOUT_S:
        left = ", ".join(sorted(keys[f.key] for f in pending))
        raise ClusterError(f"no Dask worker left at {address} for {NO_WORKERS_TIMEOUT_S:.0f} s; "
                           f"unfinished: {left}. Their stored rounds are kept: start workers "
                           "and run the experiment again to resume them")
    return since


def _wait_stopped(client: Client, futures: Sequence, say: Callable[[str], None]) -> None:
    """Wait (up to STOP_TIMEOUT_S) for every campaign not finished to see the stop event (a
    running Dask task cannot be cancelled from outside: it must return)."""
    from distributed import wait

    running = [f for f in futures if not f.done()]
    if not running:
        return
    if not client.scheduler_info()["workers"]:  # nothing runs them: nothing to wait for
        client.cancel(running)
        return
    say(f"stopping {len(running)} unfinished campaign(s) on the cluster")
    try:
        wait(running, timeout=STOP_TIMEOUT_S)
    except TimeoutError:
        say(f"{sum(not f.done() for f in running)} campaign(s) did not stop within "
            f"{STOP_TIMEOUT_S:.0f} s; a campaign's lease keeps a re-run from writing beside it")
        client.cancel(running)


def _remote(run: Callable[..., CampaignDone], job: CampaignJob, brief: Callable, topic: str,
            event: str) -> Any:
    """A campaign in a Dask worker: its lines published, its stop event watched, and a failure
    named with the worker it happened on."""
    from distributed import get_worker

    should_stop = dask_should_stop(event)
    if should_stop():
        raise CampaignCancelled(f"{job.label}: not started, the experiment failed")
    try:
        return run(job, brief, say=dask_say(topic), should_stop=should_stop)
    except CampaignCancelled:
        raise
    except Exception as exc:
        where = f"Dask worker {get_worker().address} on {socket.gethostname()}"
        raise ClusterError(f"{job.label} failed on {where}: {type(exc).__name__}: "
                           f"{' '.join(str(exc).split())}") from exc
