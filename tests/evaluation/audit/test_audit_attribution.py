"""The credit split of view run_attribution on hand-written rows, and the audit's shares of it."""

from __future__ import annotations

import pytest

from evoeye.evaluation.audit.attribution import summarise_attribution
from evoeye.evaluation.audit.summary import ScenarioAudit
from evoeye.evaluation.audit.verdicts import verdicts
from evoeye.paths import DataRoot
from evoeye.store import Warehouse
from evoeye.store.attribution import AttributionRow, write_attribution

ORACLES = ("oracle_perception", "oracle_prediction", "oracle_planning", "oracle_control")
S1 = "highway-cut-in"


def _rows(run: str, avoided_by: set[str], careful_avoids: bool, version: str = "v1"
          ) -> list[AttributionRow]:
    """The five counterfactuals of one run: the named oracles avoid the collision."""
    def row(variant: str, collided: bool) -> AttributionRow:
        return AttributionRow(S1, run, version, variant, collided, None if not collided else 2.0,
                              1.0, False)

    return [row("careful_driver", not careful_avoids),
            *(row(v, v.removeprefix("oracle_") not in avoided_by) for v in ORACLES)]


@pytest.fixture
def explained(tmp_path) -> DataRoot:
    root = DataRoot.resolve(tmp_path / "data")
    write_attribution(root, [
        *_rows("a", {"perception", "prediction"}, careful_avoids=True),  # half each
        *_rows("b", set(), careful_avoids=False),  # compound
        *_rows("c", {"planning"}, careful_avoids=True),
        *_rows("d", {"control"}, careful_avoids=True),  # not audited below
    ])
    return root


def _audit_rows(root: DataRoot, ids: list[str]) -> list[dict]:
    return Warehouse(root).query("audit_attribution", scenario_ids=ids).to_pylist()


def test_the_view_splits_one_unit_of_credit_per_run(explained: DataRoot) -> None:
    rows = Warehouse(explained).sql(
        "SELECT scenario_id, cause, share FROM run_attribution ORDER BY scenario_id, cause"
    ).to_pylist()
    got = {(r["scenario_id"], r["cause"]): r["share"] for r in rows}
    assert got == {("a", "perception"): 0.5, ("a", "prediction"): 0.5, ("b", "compound"): 1.0,
                   ("c", "planning"): 1.0, ("d", "control"): 1.0}


def test_audit_shares_over_the_audited_runs(explained: DataRoot) -> None:
    s = summarise_attribution(_audit_rows(explained, ["a", "b", "c", "x"]), collision_runs=4)
    assert (s.collision_runs, s.explained_runs, s.careful_runs) == (4, 3, 3)
    assert s.careful_avoidable == pytest.approx(2 / 3)
    assert s.careful_unavoidable == pytest.approx(1 / 3)
    assert s.credit_share == pytest.approx({"perception": 1 / 6, "prediction": 1 / 6,
                                            "planning": 1 / 3, "control": 0.0,
                                            "compound": 1 / 3})
    assert sum(s.credit_share.values()) == pytest.approx(1.0)
    assert s.oracle_avoids == pytest.approx({"perception": 1 / 3, "prediction": 1 / 3,
                                             "planning": 1 / 3, "control": 0.0})


def test_the_latest_explained_version_of_a_run_counts(explained: DataRoot) -> None:
    write_attribution(explained, _rows("b", {"control"}, careful_avoids=True, version="v2"))
    s = summarise_attribution(_audit_rows(explained, ["b"]), collision_runs=1)
    assert s.credit_share["control"] == 1.0 and s.careful_avoidable == 1.0


def test_unexplained_runs_are_not_judged(explained: DataRoot) -> None:
    assert summarise_attribution(_audit_rows(explained, ["x", "y"]), collision_runs=2) is None
    audit = ScenarioAudit(S1, runs=[])
    judged = {v.criterion: v for v in verdicts(audit)}
    assert judged["careful driver"].passed is None
    assert "evoeye explain" in judged["careful driver"].value
    assert judged["diverse causes"].passed is None


@pytest.mark.parametrize(("runs", "diverse"), [
    ({"a": {"perception"}, "b": {"prediction"}, "c": {"planning"}}, True),
    ({"a": {"perception"}, "b": {"perception"}, "c": {"planning"}}, False),  # two modules
    ({"a": {"perception"}, "b": {"perception"}, "c": {"perception"}, "d": {"prediction"},
      "e": {"planning"}}, True),  # perception at exactly 60 %
    ({"a": {"perception"}, "b": {"perception"}, "c": {"perception"}, "d": {"perception"},
      "e": {"prediction"}, "f": {"planning"}}, False),  # perception 67 %
])
def test_diverse_causes_verdict(tmp_path, runs: dict[str, set[str]], diverse: bool) -> None:
    root = DataRoot.resolve(tmp_path / "data")
    write_attribution(root, [r for run, mods in runs.items() for r in _rows(run, mods, True)])
    audit = ScenarioAudit(S1, runs=[])
    audit.attribution = summarise_attribution(_audit_rows(root, list(runs)), len(runs))
    judged = {v.criterion: v for v in verdicts(audit)}
    assert judged["diverse causes"].passed is diverse
    assert judged["careful driver"].passed is True
