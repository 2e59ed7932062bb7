"""`evoeye monitors`: every version with its scenario, family, parent, data and figures."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from evoeye.cli import app
from evoeye.paths import DataRoot
from evoeye.store.feedback import RoundRow, write_round

RUNNER = CliRunner()


def _version(root: DataRoot, folder: str, version: str, card: dict) -> None:
    path = root.path / folder / version
    path.mkdir(parents=True)
    (path / ("card.json" if folder == "monitors" else "meta.json")).write_text(json.dumps(
        {"version": version, **card}))


def _root(tmp_path) -> DataRoot:
    root = DataRoot.resolve(tmp_path / "data")
    val = {"auroc": 0.9, "auprc": 0.5, "fpr_0.05": {"f1": 0.4}}
    _version(root, "monitors", "fusion-aaa", {
        "logical_scenario": "highway-cut-in", "parent": None, "created_at": "2026-01-01",
        "data": {"train": {"runs": 400, "frames": 130_000}}, "metrics": {"val": val}})
    _version(root, "monitors", "fusion-bbb", {
        "logical_scenario": "highway-cut-in", "parent": "fusion-aaa", "created_at": "2026-01-02",
        "data": {"train": {"runs": 24, "frames": 8_000}}, "metrics": {"val": val}})
    _version(root, "baselines/aem", "aem-ccc", {
        "logical_scenario": "unprotected-intersection", "train_scenarios": 30,
        "train_windows": 9_000})
    write_round(root, RoundRow("evo-x", "highway-cut-in", "evoeye", 0, 1, "fusion-bbb", ["r"],
                               25, 12.0))
    return root


def test_the_table_names_each_versions_scenario_family_parent_data_and_role(tmp_path) -> None:
    root = _root(tmp_path)
    res = RUNNER.invoke(app, ["monitors", "--root", str(root.path)])
    assert res.exit_code == 0, res.output
    assert "3 monitor version(s)" in res.output
    line = next(x for x in res.output.splitlines() if "fusion-bbb" in x)
    for cell in ("highway-cut-in", "fusion-aaa", "24", "8,000", "90.0", "50.0", "40.0",
                 "G_1 of evo-x"):
        assert cell in line
    assert "aem-ccc" in res.output and "9,000" in res.output


def test_json_and_the_scenario_filter(tmp_path) -> None:
    root = _root(tmp_path)
    res = RUNNER.invoke(app, ["monitors", "--root", str(root.path), "--json", "--scenario",
                              "highway-cut-in"])
    assert res.exit_code == 0, res.output
    rows = json.loads(res.stdout)
    assert [r["version"] for r in rows] == ["fusion-aaa", "fusion-bbb"]
    assert rows[0]["train_runs"] == 400 and rows[0]["val_f1"] == 0.4
    assert rows[1]["parent"] == "fusion-aaa" and rows[1]["rounds"] == ["G_1 of evo-x"]


def test_a_missing_root_is_one_line(tmp_path) -> None:
    res = RUNNER.invoke(app, ["monitors", "--root", str(tmp_path / "nope")])
    assert res.exit_code == 2 and "Traceback" not in res.output
