"""Flow: ingest every new run log under a data root into the warehouse (a thin wrapper).

Ingest is idempotent, so the task may simply be retried; it is retried only when another
writer holds the warehouse lock, since any other failure would fail the same way again.
"""

from __future__ import annotations

from dataclasses import asdict
from typing import Any

from prefect import flow, get_run_logger, task
from pydantic import BaseModel, Field

from evoeye.paths import DataRoot
from evoeye.store import ingest
from evoeye.store.ingest import DEFAULT_RUNS_PER_PART
from flows.published import ingest_markdown, named, publish
from flows.runners import retry_while_locked


class IngestParams(BaseModel):
    """Where to ingest, how many runs go into one Parquet part, how many processes read logs."""

    root: str | None = None  # default: $EVOEYE_HOME or ./evoeye-data
    runs_per_part: int = Field(DEFAULT_RUNS_PER_PART, ge=1, le=10_000)
    workers: int = Field(1, ge=1, le=256)  # processes reading logs side by side

    def run_name(self) -> str:
        return f"ingest-{DataRoot.resolve(self.root).path.name}"


@task(retries=5, retry_delay_seconds=10, retry_condition_fn=retry_while_locked)
def ingest_logs(root: DataRoot, runs_per_part: int, workers: int = 1) -> dict[str, Any]:
    """One ingest pass; the IngestReport as a dict."""
    return asdict(ingest(root, runs_per_part=runs_per_part, workers=workers))


@flow(name="evoeye-ingest", log_prints=True,
      flow_run_name=named(lambda p: (p or IngestParams()).run_name()))
def ingest_flow(params: IngestParams | None = None) -> dict[str, Any]:
    """Ingest the runs of `params.root`; the report names every quarantined log."""
    params = params or IngestParams()
    root = DataRoot.resolve(params.root)
    report = ingest_logs(root, params.runs_per_part, params.workers)
    logger = get_run_logger()
    logger.info("%d runs (%d frames) ingested, %d already in, into %s",
                len(report["ingested"]), report["frames"], report["skipped"], root.warehouse)
    for log, reason in report["quarantined"]:
        logger.warning("quarantined %s: %s", log, reason)
    if report["catalog_error"]:
        logger.warning("views not refreshed: %s", report["catalog_error"])
    publish("evoeye-ingest", ingest_markdown(report, root), str(root.warehouse))
    return report


if __name__ == "__main__":
    from flows.command_line import run_from_command_line

    run_from_command_line(IngestParams, ingest_flow, __doc__)
