"""One writer per campaign, and a way to stop one between its steps.

A campaign that runs holds an exclusive `flock` on its own lock file,
`warehouse/.locks/campaign-<campaign id>.lock` (beside the warehouse's writer locks, outside the
folder of its logs), with the holder's host, PID and start time in it. A second
process that would run the same campaign — a re-run while the first is still going, on any host
of a cluster whose shared filesystem honours `flock` (docs/distributed.md) — is refused with
that line. The kernel drops the lock when its holder exits, however it exits.

`Campaign.should_stop` is asked before every run and every monitor update; when it answers yes,
the campaign raises `CampaignCancelled` and stops there. Where no Dask event carries the
request (a Prefect task runner), a stop file on the data root does (`stop_file`). What it
stored is whole (a campaign is resumable at any point): a re-run picks up from its last round.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from evoeye.paths import DataRoot
from evoeye.store.lock import LOCKS_DIR, WarehouseLockedError, WriterLock


class CampaignBusyError(RuntimeError):
    """Another process is running this campaign."""


class CampaignCancelled(RuntimeError):
    """The campaign was asked to stop (the experiment that started it failed elsewhere)."""


def lease_path(root: DataRoot, campaign_id: str) -> Path:
    return root.warehouse / LOCKS_DIR / f"campaign-{campaign_id}.lock"


def stop_file(root: DataRoot, token: str) -> Path:
    """The file whose existence asks every campaign of an experiment (`token`) to stop."""
    return root.warehouse / LOCKS_DIR / f"stop-{token}"


@contextmanager
def campaign_lease(root: DataRoot, campaign_id: str) -> Iterator[None]:
    """Hold the campaign's lock for the block; CampaignBusyError, naming the holder, if another
    process holds it."""
    path = lease_path(root, campaign_id)
    try:
        lock = WriterLock(path).__enter__()
    except WarehouseLockedError:
        holder = path.read_text(encoding="utf-8").strip() or "another process"
        raise CampaignBusyError(
            f"campaign {campaign_id} is already running ({holder}): one writer per campaign; "
            "wait for it to finish, or stop that process, and run again") from None
    try:
        yield
    finally:
        lock.__exit__(None, None, None)
