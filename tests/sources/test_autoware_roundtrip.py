"""Export then import: the lossless mode gives the native frames back; realistic rates come close.

Lossless (every topic on the 20 Hz clock, evoeye's grids): the imported runs' windows — frame
features and labels, through the warehouse — equal the native ingest's within 1e-5. Realistic
(odometry 50 Hz, objects and planning 10 Hz, control 33 Hz): the frames carry the held
messages' ages, and the features stay within the tolerances docs/autoware.md gives.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from evoeye.paths import DataRoot
from evoeye.sources.autoware.compare import feature_gaps, matched_windows
from evoeye.sources.autoware.export import export_run
from evoeye.sources.autoware.importer import import_bags
from evoeye.store import Warehouse

TOLERANCE = 1e-5
# realistic rates: the 95th percentile of |imported − native| per feature, over the slots both
# fill (measured on these runs, docs/autoware.md "What a round trip keeps"); bounds with some
# room, tight enough to catch a convention error (the rear-axle offset alone is 1.5 m)
REALISTIC_TOLERANCE = {
    "perception": 1.5,  # objects 10 Hz, held ≤ 50 ms: dx p95 1.0 m at highway closing speeds
    "prediction": 3.0,  # the older prediction resampled by age: 0.4 m near, 1.0 m at 3 s
    "plan": 0.5,  # trajectory 10 Hz read from the ego's place on it: p95 ≤ 0.3
    "control": 0.2,  # the command in force (33 Hz), up to 20 ms old: p95 ≤ 0.08
    "plan_info": 0.5,  # velocity limit at 10 Hz: target speed p95 0.26 m/s; decision exact
}
PLAN_START_M = 2e-3  # plan point 0 along the ego: native |dx| ≤ 1 mm, imported ≤ 0.25 mm off
PLAN_START_DY_M = 0.05  # across: the ego's offset from its path, odometry 10 ms old at most


def _rows(root: DataRoot, sql: str) -> list[tuple]:
    table = Warehouse(root).sql(sql)
    return list(zip(*(c.to_pylist() for c in table.columns), strict=True))


@pytest.fixture(scope="module")
def imported(sim_runs, tmp_path_factory) -> dict[str, DataRoot]:
    out = {}
    for rates in ("lossless", "realistic"):
        base = tmp_path_factory.mktemp(rates)
        bags = [export_run(log, base / "bags", rates=rates) for log in sim_runs.logs.values()]
        root = DataRoot.resolve(base / "data")
        report = import_bags(root, bags)
        assert report.failed == [] and len(report.ingest[0].ingested) == 2
        out[rates] = root
    return out


def test_lossless_import_gives_the_native_features_and_labels(sim_runs, imported,
                                                            same_windows) -> None:
    same_windows(sim_runs.root, imported["lossless"], sorted(sim_runs.logs), TOLERANCE)


def test_lossless_import_keeps_the_outcome_and_names_the_label_source(sim_runs,
                                                                      imported) -> None:
    sql = ("SELECT scenario_id, logical_scenario, collided, collision_time_s, other_actor, "
           "label_source, ads_profile FROM scenarios ORDER BY scenario_id")
    native = _rows(sim_runs.root, sql)
    back = _rows(imported["lossless"], sql)
    for n, b in zip(native, back, strict=True):
        assert n[:3] == b[:3] and n[4] == b[4] and n[6] == b[6] == "default"
        assert n[3] == pytest.approx(b[3], abs=1e-6) if n[3] is not None else b[3] is None
        assert n[5] == "simulator"
        assert b[5] == "ground_truth_objects:/simulation/ground_truth/objects"


def test_message_ages_are_null_natively_zero_lossless_and_rate_bound_realistic(
        sim_runs, imported) -> None:
    sql = ("SELECT max(age_localization_s), max(age_obstacles_s), max(age_predictions_s), "
           "max(age_plan_s), max(age_control_s), count(age_plan_s) FROM frames")
    assert _rows(sim_runs.root, sql) == [(None,) * 5 + (0,)]
    assert _rows(imported["lossless"], sql)[0][:5] == (0.0,) * 5
    ((loc, obs, pred, plan, ctrl, n),) = _rows(imported["realistic"], sql)
    assert n > 0
    # odometry every 20 ms, control every 30 ms: on a 50 ms clock at most 10 and 20 ms old
    assert loc == pytest.approx(0.01) and ctrl == pytest.approx(0.02)
    assert obs == pred == plan == pytest.approx(0.05)  # 10 Hz on a 20 Hz clock


@pytest.fixture(scope="module")
def realistic(sim_runs, imported) -> tuple[dict, dict]:
    """The native and realistic-rate windows (one frame each) of the frames both have."""
    m = matched_windows(sim_runs.root, imported["realistic"], sorted(sim_runs.logs),
                        context_len=1)
    assert sorted(set(m.scenario_id)) == sorted(sim_runs.logs)
    return m.native, m.imported


def test_realistic_rates_lose_exactly_the_last_frame_of_a_run_of_even_length(
        sim_runs, imported) -> None:
    # a frame closes when odometry stamped at or after it has arrived; odometry every 20 ms
    # from the first frame, frames every 50 ms: the last frame, at 50·(n − 1) ms, has an
    # odometry message at its time only if n is odd — else the recording ends 10 ms before it
    sql = "SELECT scenario_id, list(frame ORDER BY frame) FROM frames GROUP BY ALL"
    native = dict(_rows(sim_runs.root, sql))
    back = dict(_rows(imported["realistic"], sql))
    assert back == {sid: frames[:-1] if len(frames) % 2 == 0 else frames
                    for sid, frames in native.items()}
    assert dict(_rows(imported["lossless"], sql)) == native  # lossless keeps every frame


def test_realistic_rates_stay_within_the_documented_tolerances(realistic) -> None:
    a, b = realistic
    assert np.array_equal(a["label"], b["label"])
    # a held plan still covers the whole grid: the plan mask a monitor was trained on (always
    # full for evoeye's ADS) does not change
    assert np.array_equal(a["plan_mask"], b["plan_mask"])
    for name, bound in REALISTIC_TOLERANCE.items():
        p95 = feature_gaps(a, b, name)
        assert np.all(p95 <= bound), (name, p95)


def test_a_held_trajectory_starts_where_the_ego_is_as_evoeye_s_plans_do(realistic) -> None:
    # evoeye's ADS plans from the ego: its point 0 is level with the ego (dx within 2 mm). A
    # 10 Hz trajectory held for a frame is read from where the ego is on it, so its point 0
    # is too; read 50 ms on from its stamp instead it would be decimetres ahead or behind
    a, b = realistic
    dx_native, dx_imported = a["plan"][:, -1, 0, 1], b["plan"][:, -1, 0, 1]  # (B,)
    assert np.abs(dx_native).max() <= PLAN_START_M
    assert np.abs(dx_imported - dx_native).max() <= PLAN_START_M
    # across, the plan keeps the ego's offset from its path, as the native plan does
    dy_native, dy_imported = a["plan"][:, -1, 0, 2], b["plan"][:, -1, 0, 2]
    assert np.percentile(np.abs(dy_imported - dy_native), 95) <= PLAN_START_DY_M


def test_importing_again_adds_nothing(sim_runs, imported, tmp_path: Path) -> None:
    root = imported["lossless"]
    bags = sorted((root.path.parent / "bags").iterdir())
    again = import_bags(root, bags)
    assert again.failed == [] and again.ingest[0].ingested == []
    assert again.ingest[0].skipped == 2
    assert _rows(root, "SELECT count(*) FROM scenarios") == [(2,)]
