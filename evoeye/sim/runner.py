"""Run one concrete scenario: (scenario vector, seed) → Episode, all in memory.

The loop at 20 Hz: read the ground truth, let the ADS compute its messages from it, record the
frame, apply the control command and advance the world by one step. A run lasts `duration_s`
of simulated time and ends `post_collision_s` after the ego's first collision. A run that
raises or produces a non-finite value is returned as a failed Episode with the reason.

A *branch* (frame k, key) reseeds both random streams at the top of frame k, after the world's
state at k is read and before the ADS senses it: a run with branches is the run without them up
to frame k, and from there on an independent continuation of the same state: how much of a
collision its own randomness decided, and from when (`experiments.decided_by`). The reseeded
streams derive from (seed, k, key), so a run with the same branches is the same run.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from evoeye import __version__
from evoeye.ads import ADS, DEFAULT_PROFILE, ADSConfig, ads_profile, check_profile
from evoeye.ads.messages import FrameMessages
from evoeye.scenarios import SCENARIO_SPECS, simulable
from evoeye.scene import RoadMap, SceneState
from evoeye.sim.episode import STATUS_FAILED, STATUS_OK, Episode, Frame, Outcome, RunSpec
from evoeye.sim.footprint import min_ego_gap
from evoeye.sim.world import World
from evoeye.sim.worlds import DEFAULT_WORLD, check_world, run_variant, vary

RATE_HZ = 20.0

WorldBuilder = Callable[[dict[str, float], np.random.Generator], tuple[World, float]]


def world_builder(scenario: str) -> WorldBuilder:
    """The registered scenario's world builder (`ScenarioSpec.world`)."""
    return simulable(scenario).world_builder()


class SimulationError(RuntimeError):
    """The simulation produced something it must not (e.g. NaN)."""


@dataclass(frozen=True)
class SimConfig:
    duration_s: float = 20.0
    post_collision_s: float = 2.0
    rate_hz: float = RATE_HZ


def run_spec(
    scenario: str, params, seed: int, *, batch: str = "default", source: str = "initial",
    round: int = 0,  # noqa: A002 - the paper's name for an acquisition round
    ads: str = DEFAULT_PROFILE, world: str = DEFAULT_WORLD,
) -> RunSpec:
    """A validated RunSpec whose id is derived from (scenario, params, seed, ADS profile,
    world variant)."""
    space = simulable(scenario).space
    x = space.validate(params)
    check_profile(ads)
    check_world(world, scenario)
    return RunSpec(
        scenario=scenario, params=tuple(float(v) for v in x), seed=int(seed),
        scenario_id=space.scenario_id(x, seed, run_variant(ads, world)),
        batch=batch, source=source, round=round, ads=ads, world=world,
    )


def _seeds(seed: int) -> tuple[np.random.Generator, np.random.Generator]:
    """Independent streams for the world and for the ADS, both fixed by the run seed."""
    world_ss, ads_ss = np.random.SeedSequence(seed).spawn(2)
    return np.random.default_rng(world_ss), np.random.default_rng(ads_ss)


def _reseed(streams: Sequence[np.random.Generator], seed: int, frame: int, key: int) -> None:
    """Give every stream a fresh state from (seed, frame, key), in place: whoever holds one (the
    road, the sensors, the localiser) draws from the new state."""
    for stream, fresh in zip(streams, np.random.SeedSequence([seed, frame, key]).spawn(
            len(streams)), strict=True):
        stream.bit_generator.state = np.random.default_rng(fresh).bit_generator.state


def build_world(spec: RunSpec, world_rng: np.random.Generator | None = None) -> tuple[World, float]:
    """The world of a run and the ego's cruise speed, exactly as `run_episode` sets it up."""
    params = SCENARIO_SPECS[spec.scenario].space.as_dict(spec.params)
    world, cruise_mps = world_builder(spec.scenario)(params, world_rng or _seeds(spec.seed)[0])
    return vary(spec.world, spec.scenario, world, params, cruise_mps), cruise_mps


def scene_finite(scene: SceneState) -> bool:
    """False if any actor's position, heading or speed is NaN or infinite."""
    total = scene.x_m + scene.y_m + scene.heading_rad + scene.speed_mps
    return np.count_nonzero(np.isfinite(total)) == total.size


class Driver(Protocol):
    """What drives the ego: the ADS, or a counterfactual stand-in (an oracle-patched ADS, the
    careful reference driver). One call per frame with the ground truth; returns every message."""

    def step(self, scene: SceneState) -> FrameMessages: ...


DriverFactory = Callable[[RoadMap, np.random.Generator, ADSConfig], Driver]


def default_driver(road_map: RoadMap, rng: np.random.Generator, config: ADSConfig) -> Driver:
    """The ADS under monitoring."""
    return ADS(road_map, rng, config)


class RunLoop:
    """One run's frame loop, shared by `run_episode` and the lockstep engine
    (`evoeye.sim.lockstep`): what to read at frame k, what to record of it, when the run ends,
    and the Episode it leaves. Whatever raises inside the run goes to `fail` and the run ends as
    a failed Episode; the engines differ only in how they call `driver.step` and `world.step`."""

    def __init__(self, spec: RunSpec, config: SimConfig | None = None,
                 ads_config: ADSConfig | None = None, *, driver: DriverFactory = default_driver,
                 branches: Sequence[tuple[int, int]] = ()) -> None:
        self.spec = spec
        self.config = c = config or SimConfig()
        # a bad vector is the caller's error: raise
        simulable(spec.scenario).space.validate(spec.params)
        check_profile(spec.ads)
        check_world(spec.world, spec.scenario)
        self._reseed = dict(branches)
        if len(self._reseed) != len(branches) or any(k < 0 for k in self._reseed):
            raise ValueError(f"branches need distinct frames >= 0, got {list(branches)}")
        self._streams = _seeds(spec.seed)
        self._ads_config = ads_config
        self._driver_factory = driver
        self.dt = 1.0 / c.rate_hz
        self.n_frames = int(round(c.duration_s * c.rate_hz))
        self._post_frames = int(round(c.post_collision_s * c.rate_hz))
        self.frames: list[Frame] = []
        self.done = False
        self._collision: tuple[float, int, int | None] | None = None  # (t, frame, other actor)
        self._failure = ""
        self.road_map: RoadMap | None = None
        self.world: World | None = None
        self.driver: Driver | None = None

    def start(self) -> None:
        """Build the world and what drives the ego (may raise: `fail`)."""
        world_rng, ads_rng = self._streams
        world, cruise_mps = build_world(self.spec, world_rng)
        self.world, self.road_map = world, world.road_map
        self.driver = self._driver_factory(
            world.road_map, ads_rng,
            (self._ads_config or ads_profile(self.spec.ads)).with_cruise_speed(cruise_mps))

    def observe(self, k: int, scene: SceneState | None = None) -> SceneState:
        """The ground truth of frame k (`scene`: the world's, read for a batch of runs at once),
        at its exact frame time; reseeds the streams at a branch, after the world is read and
        before the ego senses it."""
        scene = scene or self.world.scene()
        scene.t_s = k * self.dt  # exact frame time, free of float accumulation
        if k in self._reseed:
            _reseed(self._streams, self.spec.seed, k, self._reseed[k])
        return scene

    def record(self, k: int, scene: SceneState, msgs: FrameMessages) -> bool:
        """Keep frame k; True if the world is to be stepped on (False: the run has ended; after
        its last frame, a run ends once its world has stepped, as it always has)."""
        if not (scene_finite(scene) and msgs.all_finite()):
            raise SimulationError(f"non-finite value at t={scene.t_s:.2f} s")
        self.frames.append(Frame(scene, msgs))
        if scene.ego_collision and self._collision is None:
            self._collision = (scene.t_s, k, scene.collision_actor)
        if self._collision is not None and k >= self._collision[1] + self._post_frames:
            self.done = True
        return not self.done

    def fail(self, exc: BaseException) -> None:
        """End the run as failed: a broken run is data, not a crash of the batch."""
        self._failure = f"{type(exc).__name__}: {exc}"
        self.done = True

    def episode(self) -> Episode:
        """The Episode of the ended run."""
        duration_s = len(self.frames) * self.dt
        if self._failure:
            outcome = Outcome(status=STATUS_FAILED, reason=self._failure, duration_s=duration_s)
        else:
            min_gap = min_ego_gap([f.scene for f in self.frames])  # footprint distance; 0: touch
            t, _, other = self._collision or (None, -1, None)
            outcome = Outcome(
                status=STATUS_OK, collided=t is not None, collision_time_s=t,
                other_actor=other, duration_s=duration_s,
                min_distance_m=min_gap if np.isfinite(min_gap) else None,
            )
        return Episode(
            spec=self.spec, road_map=self.road_map or RoadMap.empty(self.spec.scenario),
            outcome=outcome, software_version=__version__, rate_hz=self.config.rate_hz,
            frames=self.frames,
        )


def run_episode(
    spec: RunSpec, config: SimConfig | None = None, ads_config: ADSConfig | None = None,
    *, driver: DriverFactory = default_driver, branches: Sequence[tuple[int, int]] = (),
) -> Episode:
    """Simulate one run. Never raises for a problem inside the run: it returns a failed Episode.

    `driver` builds what drives the ego (default: the ADS); counterfactual re-simulations pass
    another factory and get the same world, the same random streams and the same frame loop.
    `branches`: (frame, key) pairs at which both streams are reseeded (module doc).
    """
    run = RunLoop(spec, config, ads_config, driver=driver, branches=branches)
    try:
        run.start()
        for k in range(run.n_frames):
            scene = run.observe(k)
            msgs = run.driver.step(scene)
            if not run.record(k, scene, msgs):
                break
            run.world.step(msgs.control.accel_cmd_mps2, msgs.control.steering_rad, run.dt)
        run.done = True
    except Exception as exc:  # noqa: BLE001 - a broken run is data, not a crash of the batch
        run.fail(exc)
    return run.episode()
