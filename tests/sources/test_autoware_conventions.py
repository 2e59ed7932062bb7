"""The stack's conventions, each checked against a hand-made case (a round trip alone would pass
with the same mistake made both ways)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from evoeye.sources.autoware.config import Mapping, Vehicle
from evoeye.sources.autoware.convert import (
    Context,
    ConversionError,
    Ego,
    TrackIds,
    objects,
    odometry,
    uuid_int,
    yaw,
)
from evoeye.sources.autoware.export import Exporter
from evoeye.sources.autoware.grids import plan_points, predictions


@pytest.fixture(scope="module")
def ex() -> Exporter:
    return Exporter(Mapping())


def test_base_link_is_the_rear_axle_centre_behind_the_body_centre(ex) -> None:
    # evoeye's ego: 5 m long, rear overhang 1 m → the rear axle 1.5 m behind the centre
    msg = ex.odometry(0, 10.0, 20.0, math.pi / 2, 7.0)  # heading +y
    assert msg.pose.pose.position.x == pytest.approx(10.0)
    assert msg.pose.pose.position.y == pytest.approx(18.5)
    ego = odometry(msg, Context())
    assert (ego.x_m, ego.y_m, ego.heading_rad, ego.speed_mps) == pytest.approx(
        (10.0, 20.0, math.pi / 2, 7.0))
    short = Context(Vehicle(length_m=4.0, rear_overhang_m=1.0))
    assert odometry(msg, short).y_m == pytest.approx(19.5)


def test_an_object_twist_is_in_the_object_frame(ex) -> None:
    # heading +y, moving along +y at 5 m/s: forward 5 in its own frame, sideways 0
    msg = ex.tracked(0, [7], ["truck"], [1.0], [2.0], [math.pi / 2], [0.0], [5.0], [8.0],
                     [2.5], [0.9])
    twist = msg.objects[0].kinematics.twist_with_covariance.twist.linear
    assert (twist.x, twist.y) == pytest.approx((5.0, 0.0))
    got = objects(msg, Context())
    assert got["track_id"] == [7] and got["obj_class"] == ["truck"]
    assert (got["vx_mps"][0], got["vy_mps"][0]) == pytest.approx((0.0, 5.0))
    assert (got["length_m"][0], got["width_m"][0]) == pytest.approx((8.0, 2.5))


def test_yaw_normalises_a_slightly_off_quaternion_and_refuses_a_wrong_one(ex) -> None:
    q = ex.b.pose(0.0, 0.0, 1.0).orientation
    q.z, q.w = q.z * 1.001, q.w * 1.001
    assert yaw(q) == pytest.approx(1.0)
    q.z, q.w = 0.0, 0.0
    with pytest.raises(ConversionError, match="norm 0 is not normalised"):
        yaw(q)


def test_uuids_keep_evoeye_track_ids_including_negative_ones(ex) -> None:
    ids = TrackIds()
    for track in (0, 5, -1, 2**40):
        assert uuid_int(ex.b.uuid(track)) == track == ids(ex.b.uuid(track))


def _uuid(raw: bytes):
    from evoeye.sources.autoware.typestore import typestore

    return typestore().types["unique_identifier_msgs/msg/UUID"](
        uuid=np.frombuffer(raw, np.uint8).copy())


def test_random_uuids_become_distinct_bigint_ids_stable_within_a_run() -> None:
    rng = np.random.default_rng(7)
    raws = [rng.bytes(16) for _ in range(2000)]
    raws += [raws[0][:8] + rng.bytes(8)]  # the same first 8 bytes: not the same object
    ids = TrackIds()
    got = [ids(_uuid(r)) for r in raws]
    assert len(set(got)) == len(raws)
    assert all(0 < i < 2**63 for i in got)  # fits BIGINT, never the ego (0) or none (-1)
    assert [ids(_uuid(r)) for r in raws] == got  # the same object keeps its id
    assert got[0] == TrackIds()(_uuid(raws[0]))  # and gets it again in another run


def test_a_hashed_id_taken_by_another_uuid_is_hashed_again() -> None:
    a, b = _uuid(bytes(range(16))), _uuid(bytes(range(1, 17)))
    ids = TrackIds()
    ids.taken.add(uuid_int(b))  # as if another object of the run had that id already
    assert ids(a) == uuid_int(a)
    assert ids(b) == uuid_int(b, salt=1) != uuid_int(b)


def test_a_held_prediction_is_resampled_at_the_frame_s_times() -> None:
    from evoeye.sources.autoware.convert import PredictedObject, PredictedPath

    t = np.arange(31) * 0.1  # pose i at the stamp + 0.1 i, pose 0 at the stamp
    path = PredictedPath(0.8, t, np.stack([10.0 * t, np.zeros_like(t)], axis=1))
    rows = predictions([PredictedObject(3, 4.0, 2.0, (path,))], 0.05, (0.0, 0.0))
    # 50 ms old: the frame's point k (k+1)·0.1 s ahead is the path's at (k+1)·0.1 + 0.05 s
    assert rows["x_m"][0][:3] == pytest.approx([1.5, 2.5, 3.5])
    # the grid it covered fresh stays whole: its last point 50 ms on along the last segment
    assert len(rows["x_m"][0]) == 30 and rows["x_m"][0][-1] == pytest.approx(30.5)


def _straight(speed_mps: float, n: int = 41, x0_m: float = 0.0):
    """A trajectory along +x at `speed_mps`, points 0.1 s apart from x0_m."""
    from evoeye.sources.autoware.convert import Trajectory

    t = np.arange(n) * 0.1
    return Trajectory(t, x0_m + speed_mps * t, np.zeros_like(t), np.zeros_like(t),
                      np.full_like(t, speed_mps), np.zeros_like(t), False)


def test_a_held_trajectory_is_resampled_from_where_the_ego_is_on_it() -> None:
    traj = _straight(20.0)
    # 0.1 s old, the ego where the trajectory expected it: the age and the pose agree
    plan = plan_points(traj, Ego(2.0, 0.0, 0.0, 20.0), 0.1, (0.0, 0.0))
    assert plan["t_rel_s"][:2] == pytest.approx([0.0, 0.1])
    assert plan["x_m"][:2] == pytest.approx([2.0, 4.0])
    assert len(plan["t_rel_s"]) == 41 and plan["x_m"][-1] == pytest.approx(82.0)
    # 0.3 m short of it and 0.4 m off the path: point 0 level with the ego, on the path (the
    # plan's lateral offset is the ego's, as evoeye's ADS plans from its route), the rest
    # 0.1 s apart from there
    plan = plan_points(traj, Ego(1.7, 0.4, 0.0, 20.0), 0.1, (0.0, 0.0))
    assert plan["x_m"][:3] == pytest.approx([1.7, 3.7, 5.7])
    assert plan["y_m"][:3] == pytest.approx([0.0, 0.0, 0.0])
    assert plan["x_m"][-1] == pytest.approx(81.7)  # the covered grid stays whole


def test_a_trajectory_starting_behind_the_ego_starts_level_with_it() -> None:
    # Autoware keeps a few metres of trajectory behind the ego: its first point is not "now"
    traj = _straight(10.0, n=61, x0_m=-5.0)
    plan = plan_points(traj, Ego(0.0, 0.0, 0.0, 10.0), 0.0, (0.0, 0.0))
    assert plan["x_m"][:2] == pytest.approx([0.0, 1.0])


def test_where_a_trajectory_dwells_its_age_places_the_ego() -> None:
    from evoeye.sources.autoware.convert import Trajectory

    # stopped for 1 s at x = 0, then away at 1 m/s²: the ego at x = 0 fits any of that second
    t = np.arange(41) * 0.1
    moving = np.clip(t - 1.0, 0.0, None)
    traj = Trajectory(t, 0.5 * moving**2, np.zeros_like(t), np.zeros_like(t), moving,
                      (t >= 1.0).astype(float), False)
    plan = plan_points(traj, Ego(0.0, 0.0, 0.0, 0.0), 0.3, (0.0, 0.0))
    assert plan["speed_mps"][:9] == pytest.approx([0.0] * 8 + [0.1])  # moves 0.7 s on


def test_the_ego_is_found_on_the_segments_heading_its_way() -> None:
    from evoeye.sources.autoware.convert import Trajectory

    # a U-turn: out along +x at y = 0, back along -x at y = 3. The ego at (5, 1) is nearer the
    # outward leg; heading -x, it is on the return leg (Autoware's nearest-segment yaw limit)
    t = np.arange(41) * 0.1
    out = t <= 2.0
    x = np.where(out, 5.0 * t, 10.0 - 5.0 * (t - 2.0))
    y = np.where(out, 0.0, 3.0)
    h = np.where(out, 0.0, np.pi)
    traj = Trajectory(t, x, y, h, np.full_like(t, 5.0), np.zeros_like(t), False)
    heading_out = plan_points(traj, Ego(5.0, 1.0, 0.0, 5.0), 0.0, (0.0, 0.0))
    heading_back = plan_points(traj, Ego(5.0, 1.0, np.pi, 5.0), 0.0, (0.0, 0.0))
    assert (heading_out["x_m"][0], heading_out["y_m"][0]) == pytest.approx((5.0, 0.0))
    assert (heading_back["x_m"][0], heading_back["y_m"][0]) == pytest.approx((5.0, 3.0))


def _shift(msg, dx: float, dy: float) -> None:
    """Move every position in an Autoware message by (dx, dy), in place."""
    import dataclasses

    if hasattr(msg, "position") and hasattr(msg, "orientation"):  # a Pose
        msg.position.x += dx
        msg.position.y += dy
        return
    for f in dataclasses.fields(msg):
        value = getattr(msg, f.name)
        for item in value if isinstance(value, list) else [value]:
            if dataclasses.is_dataclass(item):
                _shift(item, dx, dy)


def test_utm_sized_coordinates_are_re_origined_before_float32(sim_runs, messages, bag_at,
                                                              tmp_path) -> None:
    import copy

    from evoeye.log import read_run
    from evoeye.log.writer import write_run
    from evoeye.sources.autoware.bag import read_bag
    from evoeye.store.features import frame_features
    from evoeye.store.records import frames_table

    _, msgs = messages(sim_runs.safe())
    msgs = [m for m in msgs if m[0] < 1_000_000_000]
    far = []
    for t, topic, kind, msg in msgs:
        msg = copy.deepcopy(msg)
        _shift(msg, 5e5, 4.1e6)  # a UTM easting and northing
        far.append((t, topic, kind, msg))
    features = []
    for name, bag_msgs in (("near", msgs), ("far", far)):
        run = read_bag(bag_at(tmp_path / name, bag_msgs))
        log = write_run(dict(run.metadata, batch="b"), run.messages(), tmp_path / f"{name}.mcap")
        features.append(frame_features(frames_table(read_run(log), name, "p")))
    near, far_ = (f.arrays() for f in features)
    for key in ("perception", "prediction", "plan"):
        # float32 at 4.1e6 m would be 0.25–0.5 m off; re-origined, within a millimetre
        assert np.abs(near[key].astype(np.float64) - far_[key]).max() < 1e-3, key
