"""The batched sensor set gives every run what `SensorModel.detect` gives it, bit for bit.

Real runs of every scenario under two ADS profiles (their sensor configurations differ: the
cautious stack's latency) are stepped in closed loop with their own ADS. Each run's ADS stream is
copied (`_seeds`) for the per-run reference and for every batched way of sensing it — the whole
mixed batch (grouped by configuration), each profile's batch (one group), each run alone (B = 1,
also through the batched arrays) — each copy with its own localiser, so that its draws interleave
with the localiser's as in the ADS. At every frame the detections must match the reference's in
ids, dtype, shape and bytes, and every copy's stream must sit where the ADS's own stream sits.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from evoeye.ads import ADS, ads_profile
from evoeye.ads.clutter import CLUTTER_ID, GHOST_ID
from evoeye.ads.detections import DET_LENGTH, DET_WIDTH, Detections
from evoeye.ads.localization import NoisyLocalizer
from evoeye.ads.lockstep import sensing as lockstep_sensing
from evoeye.ads.lockstep.sensing import detect_batch
from evoeye.ads.messages import Localization
from evoeye.ads.sensing import SensorModel
from evoeye.batch import plan_uniform
from evoeye.scenarios import SCENARIOS
from evoeye.scene import SceneState
from evoeye.sim.runner import _seeds, build_world

PROFILES = ("default", "cautious")
RUNS_PER_PROFILE = 4
FRAMES = 64
DT = 0.05
WIDE_GAP_M = 2.5  # a segmentation gap at which close cars merge often: the merge path runs


def assert_same(ref: Detections, got: Detections, where: str) -> None:
    assert got.actor_id.dtype == ref.actor_id.dtype, where
    assert got.z.dtype == ref.z.dtype and got.z.shape == ref.z.shape, where
    assert np.array_equal(got.actor_id, ref.actor_id), where
    assert got.z.tobytes() == ref.z.tobytes(), where


class Sensing:
    """One copy of a run's ADS stream with a localiser and a sensor model on it."""

    def __init__(self, seed: int, config) -> None:
        self.rng = _seeds(seed)[1]
        self.localizer = NoisyLocalizer(config.localization, self.rng)
        self.model = SensorModel(config.sensor, self.rng)


class Run:
    """A run stepped by its own ADS, with the copies of its stream that the test senses with."""

    def __init__(self, spec) -> None:
        world_rng, self.ads_rng = _seeds(spec.seed)
        self.world, cruise = build_world(spec, world_rng)
        config = ads_profile(spec.ads).with_cruise_speed(cruise)
        self.ads = ADS(self.world.road_map, self.ads_rng, config)
        self.ref, self.mixed, self.profile, self.single = (
            Sensing(spec.seed, config) for _ in range(4))
        wide = replace(config.sensor, lidar_merge_gap_m=WIDE_GAP_M)  # no localiser: ego given
        self.wide_ref = SensorModel(wide, _seeds(spec.seed)[1])
        self.wide = SensorModel(wide, _seeds(spec.seed)[1])


def _stats(dets: list[Detections], stats: dict[str, int]) -> None:
    for d in dets:
        stats["none"] += d.z.shape[1] == 0
        stats["ghost"] += np.count_nonzero(d.actor_id == GHOST_ID)
        stats["clutter"] += np.count_nonzero(d.actor_id == CLUTTER_ID)
        stats["radar_only"] += np.count_nonzero((d.z[DET_LENGTH] == 4.5) & (d.z[DET_WIDTH] == 1.9))


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_detect_batch_is_per_run_detect_on_real_runs(scenario, monkeypatch):
    merges = []
    merge_segments = lockstep_sensing.merge_segments

    def counting(*args):
        out = merge_segments(*args)
        merges.append(np.count_nonzero(~out[0]))
        return out

    monkeypatch.setattr(lockstep_sensing, "merge_segments", counting)
    runs = [Run(spec) for ads in PROFILES
            for spec in plan_uniform(scenario, RUNS_PER_PROFILE, seed=11, ads=ads)]
    by_profile = [runs[i:i + RUNS_PER_PROFILE] for i in range(0, len(runs), RUNS_PER_PROFILE)]
    stats = dict.fromkeys(("none", "ghost", "clutter", "radar_only", "occluders"), 0)
    for k in range(FRAMES):
        scenes, controls = [], []
        for run in runs:
            scene = run.world.scene()
            scene.t_s = k * DT
            msgs = run.ads.step(scene)
            scenes.append(scene)
            controls.append((msgs.control.accel_cmd_mps2, msgs.control.steering_rad, msgs))
        assert len({s.n for s in scenes}) == 1  # one logical scenario: one number of actors
        stats["occluders"] += scenes[0].occluders is not None

        egos = [run.ref.localizer.localize(s) for run, s in zip(runs, scenes, strict=True)]
        ref = [run.ref.model.detect(s, e) for run, s, e in zip(runs, scenes, egos, strict=True)]
        for e, (_, _, msgs) in zip(egos, controls, strict=True):
            assert e == msgs.localization  # the copy's stream is the ADS's stream
        mixed = detect_batch([r.mixed.model for r in runs], scenes,
                             [r.mixed.localizer.localize(s) for r, s in zip(runs, scenes,
                                                                            strict=True)])
        profile: list[Detections] = []
        for group in by_profile:
            group_scenes = [scenes[runs.index(r)] for r in group]
            profile += detect_batch([r.profile.model for r in group], group_scenes,
                                    [r.profile.localizer.localize(s) for r, s in zip(
                                        group, group_scenes, strict=True)])
        # B = 1: `detect_batch` hands a lone run to `detect`; every other frame the batched
        # arrays are made to compute it
        alone = lockstep_sensing._detect_group if k % 2 else detect_batch
        single = [alone([r.single.model], [s], [r.single.localizer.localize(s)])[0]
                  for r, s in zip(runs, scenes, strict=True)]
        # the wide gap, with the true pose for every other run
        wide_egos = [None if i % 2 else e for i, e in enumerate(egos)]
        wide_ref = [r.wide_ref.detect(s, e) for r, s, e in zip(runs, scenes, wide_egos,
                                                                strict=True)]
        wide = detect_batch([r.wide for r in runs], scenes, wide_egos)

        for i, run in enumerate(runs):
            where = f"{scenario} run {i} ({run.ads.config.sensor.latency_s} s) frame {k}"
            for got in (mixed[i], profile[i], single[i]):
                assert_same(ref[i], got, where)
            assert_same(wide_ref[i], wide[i], where + " wide gap")
            state = run.ads_rng.bit_generator.state
            for copy in (run.ref, run.mixed, run.profile, run.single):
                assert copy.rng.bit_generator.state == state, where
            assert run.wide.rng.bit_generator.state == run.wide_ref.rng.bit_generator.state
        _stats(ref, stats)
        for run, (accel, steer, _) in zip(runs, controls, strict=True):
            run.world.step(accel, steer, DT)

    # every path of the sensor model ran: ghosts, clutter, radar-only boxes; merged segments
    # where cars drive close (the crossing traffic of the other two is never within reach)
    assert stats["ghost"] and stats["clutter"] and stats["radar_only"], stats
    if scenario == "highway-cut-in":
        assert sum(merges) > 0, (stats, len(merges))
    else:
        assert stats["occluders"] == FRAMES, stats  # buildings or parked cars in the way


def _ego_only(scene):
    """The scene with the ego alone (no other actor)."""
    return replace(scene, **{f: getattr(scene, f)[:1] for f in (
        "actor_id", "x_m", "y_m", "heading_rad", "speed_mps", "accel_mps2", "length_m",
        "width_m", "crashed")})


def test_runs_of_other_sizes_configs_and_shared_streams_are_grouped_as_per_run():
    """Scenes with no other actor, two configurations and two models on one stream in one call:
    each is what per-run detection in the order of the runs gives."""
    specs = plan_uniform("unprotected-intersection", 3, seed=5)
    worlds = [build_world(spec, _seeds(spec.seed)[0])[0] for spec in specs]
    quiet = replace(ads_profile().sensor, clutter_rate_per_frame=0.0, ghost_prob=0.0)
    configs = [ads_profile().sensor, quiet, ads_profile("cautious").sensor]
    seeds = [s.seed for s in specs] * 2

    def models():
        shared = np.random.default_rng(99)
        out = [SensorModel(configs[i % 3], _seeds(seed)[1]) for i, seed in enumerate(seeds)]
        return out + [SensorModel(configs[0], shared), SensorModel(configs[1], shared)]

    ref_models, batch_models = models(), models()
    stats = {"none": 0}
    for _ in range(30):
        scenes = [w.scene() for w in worlds]
        scenes += [_ego_only(s) for s in scenes] + scenes[:2]
        ref = [m.detect(s) for m, s in zip(ref_models, scenes, strict=True)]
        got = detect_batch(batch_models, scenes, [None] * len(scenes))
        for i, (a, b) in enumerate(zip(ref, got, strict=True)):
            assert_same(a, b, f"run {i}")
        for a, b in zip(ref_models, batch_models, strict=True):
            assert a.rng.bit_generator.state == b.rng.bit_generator.state
        stats["none"] += sum(d.z.shape[1] == 0 for d in ref)
        for w in worlds:
            w.step(0.0, 0.0, DT)
    assert stats["none"], stats  # the quiet sensor alone with the ego sees nothing
    assert detect_batch([], [], []) == []


def _dense_scene(rng: np.random.Generator, n: int, n_boxes: int) -> SceneState:
    """n cars around the ego, some bumper to bumper (merged segments), some far (radar only,
    ghosts), and n_boxes random buildings (None: no occluders)."""
    x = np.concatenate(([0.0], rng.uniform(-80.0, 170.0, n)))
    y = np.concatenate(([0.0], rng.uniform(-12.0, 12.0, n)))
    x[2::3] = x[1:-1:3] + rng.uniform(4.6, 6.0, len(x[2::3]))  # right behind the one before
    y[2::3] = y[1:-1:3]
    boxes = None
    if n_boxes is not None:
        lo = rng.uniform(-60.0, 60.0, (n_boxes, 2))
        boxes = np.concatenate((lo, lo + rng.uniform(1.0, 10.0, (n_boxes, 2))), axis=1)
    return SceneState(
        t_s=0.0, actor_id=np.arange(n + 1), x_m=x, y_m=y,
        heading_rad=rng.normal(0.0, 0.2, n + 1), speed_mps=rng.uniform(0.0, 30.0, n + 1),
        accel_mps2=np.zeros(n + 1), length_m=rng.uniform(3.5, 5.0, n + 1),
        width_m=rng.uniform(1.6, 2.1, n + 1), crashed=np.zeros(n + 1, dtype=bool),
        ego_collision=False, collision_actor=-1, occluders=boxes)


@pytest.mark.parametrize("n", [1, 7, 9, 24])
def test_dense_random_scenes_with_ragged_occluders(n):
    """More actors than any scenario has (pairwise sums of ≥ 8 terms), runs with and without
    occluders of different counts, ego given or not."""
    rng = np.random.default_rng(n)
    config = replace(ads_profile().sensor, lidar_merge_gap_m=1.0)
    ref_models = [SensorModel(config, np.random.default_rng(b)) for b in range(9)]
    batch_models = [SensorModel(config, np.random.default_rng(b)) for b in range(9)]
    for _ in range(20):
        scenes = [_dense_scene(rng, n, (None, 0, 3, 11)[b % 4]) for b in range(9)]
        egos = [None if b % 3 else Localization(0.0, 0.3, -0.2, 0.01, 12.0, 0.0)
                for b in range(9)]
        ref = [m.detect(s, e) for m, s, e in zip(ref_models, scenes, egos, strict=True)]
        got = detect_batch(batch_models, scenes, egos)
        for b in range(9):
            assert_same(ref[b], got[b], f"run {b}")
            assert ref_models[b].rng.bit_generator.state == batch_models[b].rng.bit_generator.state


def _fields(msgs) -> list:
    """Every message field of a frame, arrays as (dtype, shape, bytes): comparable with ==."""
    out = []
    for msg in (msgs.localization, msgs.obstacles, msgs.predictions, msgs.plan, msgs.control):
        for value in msg.field_values():
            out.append((value.dtype.str, value.shape, value.tobytes())
                       if isinstance(value, np.ndarray) else value)
    return out


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_an_ads_sensing_through_the_batched_arrays_publishes_the_same_messages(scenario):
    """The batched detections are C-ordered where the per-run ones sometimes are not (module
    doc): downstream of the sensors, every message of the frame is still the same, bit for bit."""
    for spec in plan_uniform(scenario, 2, seed=13, ads="cautious"):
        pair = []
        for batched in (False, True):
            world_rng, ads_rng = _seeds(spec.seed)
            world, cruise = build_world(spec, world_rng)
            ads = ADS(world.road_map, ads_rng, ads_profile(spec.ads).with_cruise_speed(cruise))
            if batched:
                sensor = ads.perception.sensor
                sensor.detect = lambda s, e, m=sensor: lockstep_sensing._detect_group(
                    [m], [s], [e])[0]
            pair.append((world, ads))
        for k in range(FRAMES):
            frames = []
            for world, ads in pair:
                scene = world.scene()
                scene.t_s = k * DT
                msgs = ads.step(scene)
                frames.append(_fields(msgs))
                world.step(msgs.control.accel_cmd_mps2, msgs.control.steering_rad, DT)
            assert frames[0] == frames[1], f"{scenario} frame {k}"
