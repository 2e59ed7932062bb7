"""The predictability check on a tiny real data root, and `evoeye predictability`."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from evoeye.batch import plan_uniform, run_batch
from evoeye.cli import app
from evoeye.evolve.predictability.check import RegimeError, check_regime, regime_runs, unseen
from evoeye.monitor import read_card
from evoeye.paths import DataRoot
from evoeye.store import RunFilter, Warehouse, ingest

# its module fixtures are built once only if its tests share a worker (pytest-xdist
# --dist loadgroup); spread over two, each worker builds them again
pytestmark = pytest.mark.xdist_group("predictability-check")

SCENARIO = "unprotected-intersection"


@pytest.fixture(scope="module")
def root(tmp_path_factory: pytest.TempPathFactory) -> tuple[DataRoot, str]:
    """20 runs and a monitor trained on their split, then 6 runs ingested after it."""
    from evoeye.monitor import train_monitor

    data = DataRoot.resolve(tmp_path_factory.mktemp("predictability") / "data")
    run_batch(plan_uniform(SCENARIO, 20, 6, batch="first"), data)
    ingest(data)
    version = train_monitor(data, SCENARIO, seed=0, epochs=1)
    run_batch(plan_uniform(SCENARIO, 6, 8, batch="later"), data)
    ingest(data)
    return data, version


def test_only_runs_the_monitor_did_not_train_on_count(root) -> None:
    data, version = root
    runs = regime_runs(data, SCENARIO)
    mask = unseen(data, read_card(data, version), runs)
    wh = Warehouse(data)
    later = set(wh.query("predictability_runs", scenario=SCENARIO, batch="later",
                         ads=None).column("scenario_id").to_pylist())
    trained = {s for split in ("train", "val") for s in wh.query(
        "select_runs", **RunFilter(logical_scenario=SCENARIO, split=split).params()
    ).column(0).to_pylist()} - later
    by_id = dict(zip(runs.scenario_id, mask, strict=True))
    assert all(by_id[s] for s in later) and not any(by_id[s] for s in trained)
    assert sum(mask) == len(runs.scenario_id) - len(trained)


def test_check_regime_reports_every_figure(root) -> None:
    data, version = root
    r = check_regime(data, SCENARIO, sample=3, seeds=2, simulate=lambda *a: 1.0)
    assert r["runs"] == 26 and r["ads_profile"] == "default" and r["monitor"]["version"] == version
    assert r["collision"]["runs"] == 26 and r["collision"]["auroc"] is not None
    assert r["monitor"]["unseen_runs"] >= 6
    assert (r["label_noise"]["thetas"], r["label_noise"]["seeds"]) == (3, 2)
    assert r["label_noise"]["collision_share"] == 1.0 and len(r["verdict"]) == 4
    assert r["boundary_noise"]["thetas"] == 3
    only = check_regime(data, SCENARIO, batch="later", sample=0)
    assert only["runs"] == 6 and only["label_noise"] is None


def test_no_runs_of_the_regime_is_a_clear_error(root) -> None:
    with pytest.raises(RegimeError, match="no finished runs of 'unprotected-intersection', "
                                          "batch 'nope'"):
        regime_runs(root[0], SCENARIO, batch="nope")


def test_cli_writes_json_and_markdown_and_re_simulates_under_the_runs_profile(root) -> None:
    data, _ = root
    result = CliRunner().invoke(app, ["predictability", "--root", str(data.path), "--scenario",
                                      SCENARIO, "--batch", "first", "--sample", "2", "--seeds",
                                      "1", "--json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.output)
    (regime,) = report["regimes"]
    assert regime["runs"] == 20 and regime["label_noise"]["thetas"] == 2
    folder = data.reports / f"predictability-{SCENARIO}-first"
    assert json.loads((folder / "predictability.json").read_text())["regimes"] == [regime]
    text = (folder / "predictability.md").read_text()
    assert "AUROC" in text and "Verdict" in text and np.isfinite(regime["collision_share"])


def test_cli_unknown_batch_is_one_line_with_a_hint(root) -> None:
    result = CliRunner().invoke(app, ["predictability", "--root", str(root[0].path), "--scenario",
                                      SCENARIO, "--batch", "nope"])
    assert result.exit_code == 2
    assert "no finished runs" in result.output and "--batch" in result.output
