"""The batched tracker gives every run what `TrackingPerception.track` gives it, bit for bit, and
leaves its latency buffer and tracker as that call leaves them.

Real runs of every scenario under two ADS profiles (their latencies differ, so do their latency
buffers and leads) are stepped in closed loop with their own ADS; each frame's detections are
the ones the run's own ADS tracked with. Each run has twin perceptions, all fed those
detections: a per-run reference (`track`) and one for every batched way of tracking it — the
whole mixed batch in interleaved order (grouped by configuration), each profile's batch, each
run alone (B = 1). Some runs' detections are thinned (every detection dropped on some frames,
the first on others, in all twins alike), so tracks coast, are pruned and are born again. At
every frame the Obstacles must match the reference's in every field (dtype, shape, bytes), and
every twin's buffer and tracker (state values and memory layout, ids, confirmed flags, next
id) must be the reference's. Twice per scenario calls made to raise come first — in a group's
array work, in a group's after another group's, in a run tracked alone by its own `track` after
another such run (put back), on a foreign perception or one given twice — and must leave every
twin as it was. B = 1 goes through the batched arrays every other frame, through the run's own
`track` on the others (small groups do, by default).
"""

from __future__ import annotations

import copy
from collections import Counter
from dataclasses import replace

import numpy as np
import pytest

from evoeye.ads import ADS, ads_profile
from evoeye.ads.detections import Detections
from evoeye.ads.lockstep import tracking as lockstep_tracking
from evoeye.ads.lockstep.tracking import track_batch
from evoeye.ads.messages import Obstacles
from evoeye.ads.perception import TrackingPerception
from evoeye.ads.tracking import VX, X
from evoeye.batch import plan_uniform
from evoeye.scenarios import SCENARIOS
from evoeye.sim.runner import _seeds, build_world

PROFILES = ("default", "cautious")
RUNS_PER_PROFILE = 4
FRAMES = 80
DT = 0.05
TWINS = ("ref", "mixed", "profile", "single")
RAISE_AT = (33, 61)  # frames at which failing calls come first


@pytest.fixture(autouse=True)
def batch_small_groups(monkeypatch):
    """Groups of two runs and more go through the batched arrays (by default only larger ones
    do: a few runs are tracked faster by their own `track`)."""
    monkeypatch.setattr(lockstep_tracking, "ALONE_MAX", 1)


class Run:
    """A run stepped by its own ADS, which records the detections it tracks with, and its twin
    perceptions."""

    def __init__(self, spec, thinned: bool) -> None:
        world_rng, ads_rng = _seeds(spec.seed)
        self.world, cruise = build_world(spec, world_rng)
        self.config = c = ads_profile(spec.ads).with_cruise_speed(cruise)
        self.ads = ADS(self.world.road_map, ads_rng, c)
        self.thinned = thinned
        own = self.ads.perception.track

        def recording(scene, detections):
            self.seen = (detections, own(scene, detections))
            return self.seen[1]

        self.ads.perception.track = recording
        self.twins = {name: TrackingPerception(c.sensor, c.tracker, c.frame_dt_s,
                                               np.random.default_rng(0)) for name in TWINS}

    def detections(self, k: int) -> Detections:
        """What the ADS tracked with this frame; thinned on some frames if this run is."""
        d = self.seen[0]
        if self.thinned and k % 9 in (4, 5, 6):  # three frames blind: confirmed tracks coast
            return Detections(d.actor_id[:0], d.z[:, :0])
        if self.thinned and k % 9 == 1:  # one detection missing
            return Detections(d.actor_id[1:], d.z[:, 1:])
        return d


def assert_same_obstacles(ref: Obstacles, got: Obstacles, where: str) -> None:
    assert type(got.t_s) is float and got.t_s == ref.t_s, where
    assert got.obj_class == ref.obj_class, where
    for name in Obstacles.field_names():
        a, b = getattr(ref, name), getattr(got, name)
        if isinstance(a, np.ndarray):
            assert type(b) is np.ndarray, (where, name)
            assert (b.dtype, b.shape) == (a.dtype, a.shape), (where, name)
            assert b.flags.c_contiguous, (where, name)
            assert b.tobytes() == a.tobytes(), (where, name)


def snapshot(p: TrackingPerception) -> tuple:
    """Everything of a perception that tracking reads or writes."""
    t = p.tracker
    arrays = [(a.dtype.str, a.shape, a.tobytes()) for a in (t.state, t.track_id, t.confirmed)]
    # the state's memory layout: the next frame's covariance matmul runs on it
    layout = (t.state.strides, t.state.flags.c_contiguous, t.state.flags.f_contiguous)
    return (*arrays, layout, type(t._next_id), t._next_id, p._pending.maxlen,
            tuple(id(d) for d in p._pending))


def run_frame(runs, by_profile, mixed_order, scenes, dets, k, monkeypatch
              ) -> list[list[Obstacles]]:
    """The Obstacles of every run by every twin (in run order)."""
    ref = [r.twins["ref"].track(s, d) for r, s, d in zip(runs, scenes, dets, strict=True)]
    mixed = [None] * len(runs)
    got = track_batch([runs[i].twins["mixed"] for i in mixed_order],
                      [scenes[i] for i in mixed_order], [dets[i] for i in mixed_order])
    for i, o in zip(mixed_order, got, strict=True):
        mixed[i] = o
    profile = []
    for group in by_profile:
        profile += track_batch([runs[i].twins["profile"] for i in group],
                               [scenes[i] for i in group], [dets[i] for i in group])
    with monkeypatch.context() as m:  # B = 1: every other frame through the batched arrays
        m.setattr(lockstep_tracking, "ALONE_MAX", 1 - k % 2)
        single = [track_batch([r.twins["single"]], [s], [d])[0]
                  for r, s, d in zip(runs, scenes, dets, strict=True)]
    return [ref, mixed, profile, single]


def failing_calls(runs, mixed_order, scenes, dets, monkeypatch) -> None:
    """Batched calls that raise at several points must leave every twin as it was."""
    twins = [runs[i].twins["mixed"] for i in mixed_order]
    args = ([scenes[i] for i in mixed_order], [dets[i] for i in mixed_order])
    before = [snapshot(p) for p in twins]
    lsa = lockstep_tracking.linear_sum_assignment
    publish = lockstep_tracking._publish
    calls = Counter()

    def lsa_counted(*a):
        calls["lsa"] += 1
        if calls["lsa"] == calls["lsa fails at"]:
            raise ValueError("assignment fails")
        return lsa(*a)

    with monkeypatch.context() as m:  # how many assignments: the last one is made to fail
        m.setattr(lockstep_tracking, "linear_sum_assignment", lsa_counted)
        track_batch(copy.deepcopy(twins), *args)
    calls["lsa fails at"], calls["lsa"] = calls["lsa"], 0

    def second_publish_fails(*a):
        calls["publish"] += 1
        if calls["publish"] == 2:  # the first group is done by now
            raise RuntimeError("publishing fails")
        return publish(*a)

    def update_fails(*a):
        raise FloatingPointError("update fails")

    lone = []  # two runs tracked alone (groups of their own), the second one raises
    for lead in (0.5, 0.75):
        p = copy.deepcopy(twins[0])
        p.lead_s = lead
        lone.append(p)

    def step_fails(z):
        t = lone[1].tracker
        t.state[X:VX] += 1.0  # changes made before the error must be undone
        t.state, t._next_id = t.state[:, :0], t._next_id + 3
        raise ArithmeticError("step fails")

    lone[1].tracker.step = step_fails
    lone_before = [snapshot(p) for p in lone]

    for patch, call_args, error in (
            (("update_tracks", update_fails), (twins, *args), FloatingPointError),
            (("linear_sum_assignment", lsa_counted), (twins, *args), ValueError),
            (("_publish", second_publish_fails), (twins, *args), RuntimeError),
            (None, (twins + [object()], [*args[0], args[0][0]], [*args[1], args[1][0]]),
             TypeError),
            (None, (twins + lone, [*args[0], *args[0][:2]], [*args[1], *args[1][:2]]),
             ArithmeticError),
            (None, (twins + twins[:1], [*args[0], args[0][0]], [*args[1], args[1][0]]),
             ValueError)):
        with monkeypatch.context() as m:
            if patch:
                m.setattr(lockstep_tracking, *patch)
            with pytest.raises(error):
                track_batch(*call_args)
        assert [snapshot(p) for p in twins] == before
        assert [snapshot(p) for p in lone] == lone_before
    assert calls["lsa"] == calls["lsa fails at"] > 1 and calls["publish"] == 2, calls


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_track_batch_is_per_run_track_on_real_runs(scenario, monkeypatch):
    specs = [s for ads in PROFILES for s in plan_uniform(scenario, RUNS_PER_PROFILE, seed=13,
                                                          ads=ads)]
    runs = [Run(spec, thinned=i % RUNS_PER_PROFILE == RUNS_PER_PROFILE - 1)
            for i, spec in enumerate(specs)]
    by_profile = [range(i, i + RUNS_PER_PROFILE) for i in range(0, len(runs), RUNS_PER_PROFILE)]
    mixed_order = [i for pair in zip(*by_profile, strict=True) for i in pair][::-1]
    stats = Counter()
    for k in range(FRAMES):
        scenes = []
        for run in runs:
            scene = run.world.scene()
            scene.t_s = k * DT
            msgs = run.ads.step(scene)
            scenes.append(scene)
            run.world.step(msgs.control.accel_cmd_mps2, msgs.control.steering_rad, DT)
        dets = [r.detections(k) for r in runs]
        if k in RAISE_AT:
            failing_calls(runs, mixed_order, scenes, dets, monkeypatch)
        tracks_before = [r.twins["ref"].tracker.state.shape[1] for r in runs]
        outs = run_frame(runs, by_profile, mixed_order, scenes, dets, k, monkeypatch)

        for i, run in enumerate(runs):
            where = f"{scenario} run {i} ({run.config.sensor.latency_s} s) frame {k}"
            ref = run.twins["ref"]
            if not run.thinned:  # the reference twin is the ADS's own perception
                assert_same_obstacles(run.seen[1], outs[0][i], where)
                assert snapshot(run.ads.perception)[:-1] == snapshot(ref)[:-1], where
            for name, out in zip(TWINS[1:], outs[1:], strict=True):
                assert_same_obstacles(outs[0][i], out[i], f"{where} {name}")
                assert snapshot(run.twins[name]) == snapshot(ref), f"{where} {name}"
            trk = ref.tracker
            stepped = len(ref._pending) == ref._pending.maxlen
            stats["stepped"] += stepped
            stats["no detections"] += stepped and dets[i].z.shape[1] == 0
            stats["no tracks"] += stepped and tracks_before[i] == 0
            stats["tracks, no detections"] += stepped and tracks_before[i] > 0 and (
                dets[i].z.shape[1] == 0)
            stats["fortran-ordered"] += trk.state.shape[1] > 1 and not trk.state.flags.c_contiguous
            stats["published"] += len(outs[0][i].track_id)
            stats["coasting"] += np.count_nonzero(trk.state[-1] > 0)

    assert stats["stepped"] and stats["stepped"] < FRAMES * len(runs), stats  # buffer filling
    # every path ran: runs without detections (with and without tracks), without tracks,
    # coasting tracks, states in Fortran order (after a prune)
    for key in ("no detections", "no tracks", "tracks, no detections", "fortran-ordered",
                "published", "coasting"):
        assert stats[key], (key, stats)


def test_one_group_with_buffers_filling_at_different_frames_and_other_configs():
    """Perceptions of one group whose latency buffers differ (no lead: latencies 0.25, 0.1 and
    0 s share a configuration) or that join late, so that some runs of a group step and some
    do not yet; and a tracker whose confirmed tracks die before its tentative ones (a coast
    limit below the tentative miss limit: pruning only once a track exceeds the latter)."""
    runs = [Run(spec, thinned=i == 1)
            for i, spec in enumerate(plan_uniform("highway-cut-in", 2, seed=5))]
    base = runs[0].config
    odd = replace(base.tracker, confirm_hits=2, tentative_max_misses=3, max_coast_frames=1)
    configs = [(replace(base.sensor, latency_s=lat, compensate_latency=False), base.tracker, 0)
               for lat in (0.25, 0.1, 0.0)]
    configs += [(base.sensor, odd, 0), (replace(base.sensor, compensate_latency=False),
                                        base.tracker, 12)]  # the last joins at frame 12
    twins = [{(i, r): TrackingPerception(sensor, tracker, DT, np.random.default_rng(0))
              for i, (sensor, tracker, _) in enumerate(configs) for r in range(2)}
             for _ in range(2)]  # per-run and batched, per config, fed each run's detections
    stats = Counter()
    for k in range(60):
        scenes, dets = [], []
        for run in runs:
            scene = run.world.scene()
            scene.t_s = k * DT
            msgs = run.ads.step(scene)
            run.world.step(msgs.control.accel_cmd_mps2, msgs.control.steering_rad, DT)
            scenes.append(scene)
            dets.append(run.detections(k))
        going = [i for i, c in enumerate(configs) if k >= c[2]]
        feeds = [(i, r) for i in going for r in range(2)][::-1]
        ref = [twins[0][f].track(scenes[f[1]], dets[f[1]]) for f in feeds]
        got = track_batch([twins[1][f] for f in feeds], [scenes[r] for _, r in feeds],
                          [dets[r] for _, r in feeds])
        for f, a, b in zip(feeds, ref, got, strict=True):
            assert_same_obstacles(a, b, f"twin {f} frame {k}")
            assert snapshot(twins[1][f]) == snapshot(twins[0][f]), f"twin {f} frame {k}"
        full = {len(t._pending) == t._pending.maxlen for (i, _), t in twins[0].items()
                if i != 3 and k >= configs[i][2]}
        stats["some of a group step"] += len(full) == 2
        for r in range(2):
            odd_state = twins[0][3, r].tracker.state
            stats["odd coasting"] += np.count_nonzero((odd_state[-1] > 1) & (odd_state[-2] >= 2))
    assert stats["some of a group step"] and stats["odd coasting"], stats


def test_empty_batch_and_runs_before_the_buffer_fills():
    assert track_batch([], [], []) == []
    spec = plan_uniform("highway-cut-in", 1, seed=3)[0]
    run = Run(spec, thinned=False)
    scene = run.world.scene()
    ref, got = (run.twins[n] for n in ("ref", "single"))
    empty = Detections(np.zeros(0, dtype=np.int64), np.zeros((10, 0)))
    for _ in range(8):
        assert_same_obstacles(ref.track(scene, empty), track_batch([got], [scene], [empty])[0],
                              "empty")
        assert snapshot(got) == snapshot(ref)
    with pytest.raises(ValueError):
        track_batch([got], [scene, scene], [empty])
