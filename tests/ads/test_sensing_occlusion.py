"""Static occluders (buildings) block the sensors' line of sight."""

import numpy as np

from evoeye.ads.sensing import line_of_sight_blocked

BOX = np.array([[10.0, 10.0, 20.0, 20.0]])


def test_a_segment_through_a_box_is_blocked_and_one_beside_it_is_not():
    x = np.array([30.0, 30.0, 15.0, 5.0])
    y = np.array([30.0, 5.0, 15.0, 30.0])
    assert line_of_sight_blocked(0.0, 0.0, x, y, BOX).tolist() == [True, False, True, False]


def test_a_segment_that_stops_short_of_a_box_and_axis_parallel_ones():
    x = np.array([8.0, 15.0, 25.0])
    y = np.array([8.0, 0.0, 15.0])
    assert line_of_sight_blocked(0.0, 15.0, x, y, BOX).tolist() == [False, False, True]
    assert not line_of_sight_blocked(0.0, 0.0, x, y, None).any()


def test_buildings_hide_crossing_traffic_from_the_ads_until_the_corner_opens():
    from evoeye.ads.config import SensorConfig
    from evoeye.ads.sensing import SensorModel
    from evoeye.scene import SceneState
    from evoeye.sim.intersection import _buildings

    def seen(ego_y):
        scene = SceneState(
            t_s=0.0, actor_id=np.array([0, 1]), x_m=np.array([2.0, 30.0]),
            y_m=np.array([ego_y, -2.0]), heading_rad=np.array([-np.pi / 2, np.pi]),
            speed_mps=np.zeros(2), accel_mps2=np.zeros(2), length_m=np.full(2, 5.0),
            width_m=np.full(2, 2.0), crashed=np.zeros(2, dtype=bool), ego_collision=False,
            collision_actor=-1, occluders=_buildings())
        model = SensorModel(SensorConfig(clutter_rate_per_frame=0.0, ghost_prob=0.0),
                            np.random.default_rng(0))
        return sum(1 in model.detect(scene).actor_id for _ in range(20))

    assert seen(40.0) == 0  # 30 m east of the box, behind the south-east building
    assert seen(14.0) >= 15  # at the box: in plain sight
