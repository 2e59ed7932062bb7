"""Counterfactual re-simulation of a collision run: the same scenario and seed, one part of the
driving replaced (`evoeye explain`).

Every variant runs through `run_episode` with another driver factory, so the world, its random
stream and the frame loop are the factual run's; a variant runs identically until its
substitute first acts differently. Variants (the `attribution` table's names):

* `oracle_perception` / `oracle_prediction` / `oracle_planning` / `oracle_control`: the ADS with
  one module swapped for its oracle (`evoeye.ads.oracle`);
* `careful_driver`: the careful reference driver (`CarefulDriver`).

"Avoided" means the ego has no collision at all in the counterfactual; being struck from behind
counts as not avoided (conservative), and is recorded in `struck_from_behind`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from evoeye.ads import ADS, ADSConfig, ads_profile
from evoeye.ads.messages import ControlCommand, FrameMessages
from evoeye.ads.oracle import (
    GroundTruthPerception,
    IdealController,
    TrueFuturePredictor,
    TrueFutures,
    careful_planner,
)
from evoeye.boxes import box_corners, box_gaps
from evoeye.scene import RoadMap, SceneState
from evoeye.sim.episode import STATUS_OK, Episode, RunSpec
from evoeye.sim.runner import DriverFactory, SimConfig, run_episode

REACTION_S = 0.75  # the careful driver reacts this long after the danger shows …
BRAKE_DECEL_MPS2 = 7.59  # … then brakes, ramping to this deceleration (UN R157's driver model)
BRAKE_RAMP_S = 0.6  # … in this long
CV_HORIZON_S = 3.0  # the danger: the constant-velocity futures overlap within this horizon …
CV_STEP_S = 0.1  # … checked at this spacing
PREDICTION_ITERATIONS = 3  # oracle prediction: at most this many re-simulations


# -- the careful reference driver ----------------------------------------------------------------
def cv_overlap_time(scenes: list[SceneState], partner: int) -> float | None:
    """The first frame time at which the ego's and `partner`'s constant-velocity futures (true
    state, oriented boxes, constant heading) overlap within CV_HORIZON_S; None if never."""
    tau = np.arange(0.0, CV_HORIZON_S + 1e-9, CV_STEP_S)  # (T,)
    rows, times = [], []
    for sc in scenes:
        hit = np.flatnonzero(sc.actor_id == partner)
        if hit.size:
            rows.append([(sc.x_m[i], sc.y_m[i], sc.heading_rad[i], sc.speed_mps[i],
                          sc.length_m[i], sc.width_m[i]) for i in (0, int(hit[0]))])
            times.append(sc.t_s)
    if not rows:
        return None
    s = np.asarray(rows)  # (F, 2, 6): ego, partner × x, y, heading, speed, length, width
    x = s[..., 0, None] + s[..., 3, None] * np.cos(s[..., 2, None]) * tau  # (F, 2, T)
    y = s[..., 1, None] + s[..., 3, None] * np.sin(s[..., 2, None]) * tau

    def boxes(j: int) -> np.ndarray:  # (F·T, 4, 2)
        shape = x[:, j].shape
        return box_corners(x[:, j].ravel(), y[:, j].ravel(),
                           np.broadcast_to(s[:, j, 2, None], shape).ravel(),
                           np.broadcast_to(s[:, j, 4, None], shape).ravel(),
                           np.broadcast_to(s[:, j, 5, None], shape).ravel())

    overlap = (box_gaps(boxes(0), boxes(1)) <= 0.0).reshape(len(times), -1).any(axis=1)  # (F,)
    first = np.flatnonzero(overlap)
    return float(times[int(first[0])]) if first.size else None


def careful_reaction_time(factual: Episode) -> float | None:
    """When the careful driver starts braking: REACTION_S after the CV futures of the ego and
    the factual collision partner first overlap; None without a partner or an overlap."""
    partner = factual.outcome.other_actor
    if partner is None or partner < 0:
        return None
    t = cv_overlap_time([f.scene for f in factual.frames], partner)
    return None if t is None else t + REACTION_S


class CarefulDriver:
    """The ADS drives (and keeps running, so its random streams stay aligned) until `react_s`;
    from then on the ego brakes along its own path, steering as the ADS commands, with the
    deceleration ramping linearly from the ADS's own (if braking) to BRAKE_DECEL_MPS2 in
    BRAKE_RAMP_S."""

    def __init__(self, ads: ADS, react_s: float | None) -> None:
        self.ads = ads
        self.react_s = react_s
        self._a0_mps2: float | None = None  # the ADS's accel when the driver took over

    def step(self, scene: SceneState) -> FrameMessages:
        msgs = self.ads.step(scene)
        if self.react_s is None or scene.t_s < self.react_s - 1e-9:
            return msgs
        cmd = msgs.control
        if self._a0_mps2 is None:
            self._a0_mps2 = min(cmd.accel_cmd_mps2, 0.0)
        accel = brake_profile(scene.t_s - self.react_s, self._a0_mps2)
        limit = self.ads.config.control.accel_min_mps2
        msgs.control = ControlCommand(t_s=cmd.t_s, throttle=0.0, brake=accel / limit,
                                      steering_rad=cmd.steering_rad, accel_cmd_mps2=accel)
        return msgs


def brake_profile(since_s: float, a0_mps2: float = 0.0) -> float:
    """The careful driver's acceleration since_s after it reacted: linear from a0_mps2 to
    −BRAKE_DECEL_MPS2 over BRAKE_RAMP_S, then held."""
    f = min(max(since_s / BRAKE_RAMP_S, 0.0), 1.0)
    return a0_mps2 + (-BRAKE_DECEL_MPS2 - a0_mps2) * f


# -- variants ------------------------------------------------------------------------------------
def with_module(attr: str, build: Callable[[ADS], object]) -> DriverFactory:
    """A driver factory: the ADS with its module `attr` replaced by `build(ads)`."""
    def factory(road_map: RoadMap, rng: np.random.Generator, config: ADSConfig) -> ADS:
        ads = ADS(road_map, rng, config)
        setattr(ads, attr, build(ads))
        return ads
    return factory


def careful_driver(react_s: float | None) -> DriverFactory:
    def factory(road_map: RoadMap, rng: np.random.Generator, config: ADSConfig) -> CarefulDriver:
        return CarefulDriver(ADS(road_map, rng, config), react_s)
    return factory


def true_futures(episode: Episode) -> TrueFutures:
    return TrueFutures.from_scenes([f.scene for f in episode.frames], 1.0 / episode.rate_hz)


@dataclass(frozen=True)
class VariantResult:
    """How one counterfactual ended."""

    variant: str
    collided: bool
    collision_time_s: float | None
    min_distance_m: float | None
    struck_from_behind: bool  # the first collision is another actor running into the ego's rear
    simulations: int = 1  # re-simulations it took (oracle prediction iterates)
    converged: bool = True  # oracle prediction: the last two outcomes agreed
    react_s: float | None = None  # careful driver: when it started braking


def struck_from_behind(episode: Episode) -> bool:
    """The ego's first collision is with an actor behind it, heading the same way (±45°)."""
    o = episode.outcome
    if not o.collided or o.other_actor is None:
        return False
    sc = next(f.scene for f in episode.frames if f.scene.t_s >= o.collision_time_s - 1e-9)
    hit = np.flatnonzero(sc.actor_id == o.other_actor)
    if not hit.size:
        return False
    i, h = int(hit[0]), float(sc.heading_rad[0])
    ahead_m = (sc.x_m[i] - sc.x_m[0]) * math.cos(h) + (sc.y_m[i] - sc.y_m[0]) * math.sin(h)
    dh = (float(sc.heading_rad[i]) - h + math.pi) % (2 * math.pi) - math.pi
    return bool(ahead_m < 0.0 and abs(dh) < math.pi / 4)


def result(variant: str, episode: Episode, **extra) -> VariantResult:
    o = episode.outcome
    if o.status != STATUS_OK:
        raise RuntimeError(f"{variant} re-simulation failed: {o.reason}")
    return VariantResult(variant, o.collided, o.collision_time_s, o.min_distance_m,
                         struck_from_behind(episode), **extra)


Variant = Callable[[Episode, SimConfig, ADSConfig], VariantResult]


def _module_variant(name: str, attr: str, build: Callable[[ADS], object]) -> Variant:
    def run(factual: Episode, sim: SimConfig, ads_config: ADSConfig) -> VariantResult:
        return result(name, run_episode(factual.spec, sim, ads_config,
                                        driver=with_module(attr, build)))
    return run


def _oracle_prediction(factual: Episode, sim: SimConfig, ads_config: ADSConfig) -> VariantResult:
    """True futures from the factual run; since NPCs react to the ego, re-simulate with the
    counterfactual's own ground truth as the futures until (collided, collision time) repeats,
    at most PREDICTION_ITERATIONS times."""
    source, previous, episode, n, converged = factual, None, factual, 0, False
    for n in range(1, PREDICTION_ITERATIONS + 1):  # noqa: B007 - n is reported
        futures = true_futures(source)
        episode = run_episode(factual.spec, sim, ads_config, driver=with_module(
            "predictor", lambda ads, f=futures: TrueFuturePredictor(f, ads.config.prediction)))
        key = (episode.outcome.collided, episode.outcome.collision_time_s)
        converged = key == previous
        if converged:
            break
        previous, source = key, episode
    return result("oracle_prediction", episode, simulations=n, converged=converged)


def _careful_driver(factual: Episode, sim: SimConfig, ads_config: ADSConfig) -> VariantResult:
    react_s = careful_reaction_time(factual)
    episode = run_episode(factual.spec, sim, ads_config, driver=careful_driver(react_s))
    return result("careful_driver", episode, react_s=react_s)


VARIANTS: dict[str, Variant] = {
    "careful_driver": _careful_driver,
    "oracle_perception": _module_variant(
        "oracle_perception", "perception", lambda ads: GroundTruthPerception()),
    "oracle_prediction": _oracle_prediction,
    "oracle_planning": _module_variant(
        "oracle_planning", "planner", lambda ads: careful_planner(
            ads.road_map, ads.config.planning, ads.config.cruise_speed_mps,
            ads.config.frame_dt_s)),
    "oracle_control": _module_variant(
        "oracle_control", "controller",
        lambda ads: IdealController(ads.config.control, ads.config.frame_dt_s)),
}
# the variants that replace one module by its oracle, in pipeline order
ORACLES = tuple(v for v in VARIANTS if v.startswith("oracle_"))


def avoided_by(results: Sequence[VariantResult]) -> list[str]:
    """The modules (pipeline order, without the "oracle_" prefix) whose oracle variant among
    `results` ended without a collision: the collision's root causes."""
    by = {r.variant: r for r in results}
    return [o.removeprefix("oracle_") for o in ORACLES if o in by and not by[o].collided]


class NotACollisionError(ValueError):
    """The run to explain does not collide when re-simulated (another software version?)."""


@dataclass(frozen=True)
class Explanation:
    """Every variant of one collision run."""

    spec: RunSpec
    collision_time_s: float
    other_actor: int | None
    variants: tuple[VariantResult, ...]


def explain_run(spec: RunSpec, sim: SimConfig | None = None, ads_config: ADSConfig | None = None,
                variants: tuple[str, ...] = tuple(VARIANTS)) -> Explanation:
    """Re-simulate the factual run, then each variant. Raises NotACollisionError if the factual
    re-simulation does not collide."""
    sim, ads_config = sim or SimConfig(), ads_config or ads_profile(spec.ads)
    factual = run_episode(spec, sim, ads_config)
    o = factual.outcome
    if o.status != STATUS_OK or not o.collided:
        why = f" (it failed: {o.reason})" if o.status != STATUS_OK else ""
        raise NotACollisionError(f"{spec.scenario_id}: the re-simulated run does not collide"
                                 f"{why}; was it simulated by another software version?")
    return Explanation(spec, float(o.collision_time_s), o.other_actor,
                       tuple(VARIANTS[v](factual, sim, ads_config) for v in variants))
