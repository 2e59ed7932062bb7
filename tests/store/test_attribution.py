"""Table attribution: round trip, idempotence, and the cause derived in SQL."""

from __future__ import annotations

import pyarrow.parquet as pq
import pytest

from evoeye.paths import DataRoot
from evoeye.store import Warehouse
from evoeye.store.attribution import (
    ATTRIBUTION_TABLE,
    AttributionRow,
    explained_keys,
    read_attribution,
    write_attribution,
)
from evoeye.store.schema import canonical_schema, declared_schema

ORACLES = ("oracle_perception", "oracle_prediction", "oracle_planning", "oracle_control")


def run_rows(run: str, avoiding: set[str], careful_avoids: bool = True, version: str = "v1",
             scenario: str = "highway-cut-in") -> list[AttributionRow]:
    """The five variant rows of one run; the oracles in `avoiding` avoid the collision."""
    rows = [AttributionRow(scenario, run, version, "careful_driver", not careful_avoids,
                           None if careful_avoids else 2.0, 0.5, False)]
    for o in ORACLES:
        hit = o not in avoiding
        rows.append(AttributionRow(scenario, run, version, o, hit, 2.5 if hit else None,
                                   0.0 if hit else 1.2, False if hit else None))
    return rows


def test_round_trip_matches_the_ddl(root: DataRoot) -> None:
    rows = run_rows("r1", {"oracle_planning"})
    assert write_attribution(root, rows) == 5
    parts = list(root.table_dir(ATTRIBUTION_TABLE).glob("*.parquet"))
    assert len(parts) == 1
    assert canonical_schema(pq.read_schema(parts[0])) == declared_schema(ATTRIBUTION_TABLE)
    back = read_attribution(root).to_pylist()
    assert [(r["variant"], r["collided"], r["collision_time_s"], r["struck_from_behind"])
            for r in back] == sorted((r.variant, r.collided, r.collision_time_s,
                                      r.struck_from_behind) for r in rows)
    assert len({r["part_id"] for r in back}) == 1


def test_writing_again_adds_nothing_and_a_new_version_is_a_new_key(root: DataRoot) -> None:
    write_attribution(root, run_rows("r1", set()))
    assert write_attribution(root, run_rows("r1", {"oracle_control"})) == 0
    assert write_attribution(root, run_rows("r1", set()) + run_rows("r2", set())) == 5
    assert write_attribution(root, run_rows("r1", set(), version="v2")) == 5
    assert len(list(root.table_dir(ATTRIBUTION_TABLE).glob("*.parquet"))) == 3
    assert len(explained_keys(root)) == 15
    assert len(explained_keys(root, "v2")) == 5
    stored = read_attribution(root, "v1").to_pylist()
    assert not any(r["variant"] == "oracle_control" and not r["collided"] for r in stored)


def shares(root: DataRoot) -> dict[tuple[str, str], float]:
    rows = Warehouse(root).sql("SELECT scenario_id, cause, share FROM run_attribution")
    return {(r["scenario_id"], r["cause"]): r["share"] for r in rows.to_pylist()}


def test_credit_is_split_among_the_avoiding_oracles_or_compound(root: DataRoot) -> None:
    write_attribution(root, run_rows("two", {"oracle_perception", "oracle_planning"})
                      + run_rows("none", set(), careful_avoids=False)
                      + run_rows("one", {"oracle_control"})
                      + run_rows("partial", {"oracle_control"})[:3])  # not all oracles stored
    assert shares(root) == {
        ("two", "perception"): 0.5, ("two", "planning"): 0.5, ("none", "compound"): 1.0,
        ("one", "control"): 1.0,
    }
    careful = Warehouse(root).sql(
        "SELECT DISTINCT scenario_id, careful_driver_avoids FROM run_attribution").to_pylist()
    assert {r["scenario_id"]: r["careful_driver_avoids"] for r in careful} == {
        "two": True, "none": False, "one": True}


def test_attribution_shares_sum_to_one_per_scenario(root: DataRoot) -> None:
    write_attribution(root, run_rows("a", {"oracle_perception", "oracle_prediction"})
                      + run_rows("b", set(), careful_avoids=False)
                      + run_rows("c", {"oracle_prediction"}, scenario="unprotected-intersection"))
    rows = Warehouse(root).sql("SELECT * FROM attribution_shares").to_pylist()
    by = {(r["logical_scenario"], r["cause"]): r for r in rows}
    assert by[("highway-cut-in", "perception")]["share"] == pytest.approx(0.25)
    assert by[("highway-cut-in", "prediction")]["share"] == pytest.approx(0.25)
    assert by[("highway-cut-in", "compound")]["share"] == pytest.approx(0.5)
    assert by[("highway-cut-in", "compound")]["runs"] == 2
    assert by[("highway-cut-in", "compound")]["careful_avoided"] == 1
    assert by[("unprotected-intersection", "prediction")]["share"] == 1.0
    for ls in ("highway-cut-in", "unprotected-intersection"):
        assert sum(r["share"] for r in rows if r["logical_scenario"] == ls) == pytest.approx(1.0)


def test_an_empty_table_reads_as_the_declared_one(root: DataRoot) -> None:
    assert read_attribution(root).num_rows == 0
    assert Warehouse(root).sql("SELECT * FROM run_attribution").num_rows == 0
