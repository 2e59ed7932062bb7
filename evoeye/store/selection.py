"""Which runs: splits by scenario (seeded) and subsets of runs, both answered in SQL."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

import duckdb
import pyarrow as pa

from evoeye.splits import SPLITS, SplitSpec
from evoeye.store.sqlfiles import query


@dataclass(frozen=True)
class RunFilter:
    """A subset of runs; None means "any". Only runs with status 'ok' by default."""

    logical_scenario: str | None = None
    split: str | None = None  # train / val / test under `splits`
    source: str | None = None
    min_round: int | None = None
    max_round: int | None = None
    collided: bool | None = None  # True: violation runs only; False: collision-free only
    status: str | None = "ok"
    splits: SplitSpec = field(default_factory=SplitSpec)

    def __post_init__(self) -> None:
        if self.split is not None and self.split not in SPLITS:
            raise ValueError(f"split must be one of {SPLITS}, got {self.split!r}")

    def params(self) -> dict[str, object]:
        """The `$name` parameters of warehouse/queries/select_runs.sql."""
        p = {k: v for k, v in asdict(self).items() if k != "splits"}
        return {**p, **asdict(self.splits)}


Runs = RunFilter | Sequence[str] | str | None


def select_runs(con: duckdb.DuckDBPyConnection, runs: Runs = None) -> pa.Table:
    """The scenario ids (one column, `scenario_id`) of a subset of runs.

    `runs` is a RunFilter, an explicit list of scenario ids, or any SQL query over the
    warehouse views returning a `scenario_id` column; None means every run with status 'ok'.
    """
    if runs is None:
        runs = RunFilter()
    if isinstance(runs, RunFilter):
        return con.sql(query("select_runs"), params=runs.params()).to_arrow_table()
    if isinstance(runs, str):
        return con.sql(runs).select("scenario_id").to_arrow_table()
    return pa.table({"scenario_id": pa.array(list(runs), pa.string())})
