"""The safety supervisor: the ADS with a runtime monitor beside it and a fallback that takes over
on the monitor's alarm (`evoeye supervise`).

A driver in the loop, like the careful reference driver of `counterfactual.py`: `run_episode`
runs it with the same world, random streams and frame loop as the unsupervised run. The ADS runs
every frame (so its random streams stay aligned), the risk callable scores the ADS's messages of
the frame, and the supervisor decides what reaches the actuators. The monitor is passed in as
that callable: this layer knows no monitor and no warehouse.

Trigger: the alarm is K consecutive frames with score > threshold (`RuntimeMonitor`'s rule).
Fallback, a minimal-risk manoeuvre (`FallbackConfig`): from the alarm, after the brakes' dead
time, the deceleration ramps at a bounded jerk to its target and is held (optionally pausing at
a partial stage first). The default, `production`, is in-lane emergency braking at 9 m/s²
reached at 30 m/s³; `comfort` is the firm 6 m/s² at 10 m/s³ of the first supervisions. The ego
keeps to its lane (the ADS's steering along its planned path), never brakes less than the ADS
itself asks (the ADS's AEB stays in force) and never reverses; at standstill it is held still.
The fallback ends once the score has stayed at or below the threshold for `hold_s`; control
then goes back to the ADS through a jerk-limited hand-back (the acceleration rises at most at
`jerk_mps3` until it meets the ADS's command). Everything after is closed loop: the NPCs react
to the braking ego, and whoever hits it is recorded by the world like any contact.

Thresholds share a simulation while they agree on every decision: a supervised run is the
unsupervised run until its first alarm, and two thresholds that engage and release at the same
frames drive the same run. `SupervisedDriver` therefore carries a group of thresholds, follows
the first, and hands back (`forks`) those whose decision differs at some frame; each of those
groups is simulated again from scratch, identical up to that frame (determinism).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from evoeye.ads import ADS, ADSConfig
from evoeye.ads.messages import ControlCommand, FrameMessages
from evoeye.scene import RoadMap, SceneState
from evoeye.sim.episode import Episode, RunSpec
from evoeye.sim.npc import MAX_DECEL_MPS2
from evoeye.sim.runner import DriverFactory, SimConfig, default_driver, run_episode

Risk = Callable[[FrameMessages], float]  # one frame's ADS messages → risk score, in frame order
MODES = ("nominal", "braking", "holding", "handback")  # what drives the ego (SupervisorState)


@dataclass(frozen=True)
class FallbackConfig:
    """The minimal-risk manoeuvre and when it ends (module doc). The defaults are `production`
    (FALLBACKS): in-lane emergency braking at the tyres' limit, reached at the ADS's AEB jerk.
    No stage by default: on highway-cut-in a 4 m/s² stage of 0.3 s let an alarm 1 s before the
    collision prevent 26 % of them instead of 77 %, and spared no false brake a rear-end
    (experiments/fallback_price.py, docs/world.md)."""

    decel_mps2: float = 9.0  # the tyres' limit (npc.MAX_DECEL_MPS2), beyond the ADS's AEB (8)
    jerk_mps3: float = 30.0  # the deceleration ramps (and the hand-back rises) at most this fast
    onset_s: float = 0.1  # the brakes' dead time (ADSConfig.control.brake_dead_time_s)
    hold_s: float = 1.0  # it ends once the score stays at or below the threshold this long
    standstill_mps: float = 0.1  # at or below this speed the ego is held still
    stage_decel_mps2: float = 0.0  # staged braking: the ramp first stops at this deceleration …
    stage_s: float = 0.0  # … for this long from its start, then goes on to decel_mps2 (0: none)

    def __post_init__(self) -> None:
        if min(self.decel_mps2, self.jerk_mps3) <= 0 or min(self.onset_s, self.hold_s,
                                                             self.standstill_mps) < 0:
            raise ValueError(f"fallback decel and jerk must be > 0, times and speeds >= 0: {self}")
        if self.decel_mps2 > MAX_DECEL_MPS2:
            raise ValueError(f"fallback decel {self.decel_mps2} m/s² is beyond what the tyres "
                             f"give ({MAX_DECEL_MPS2} m/s², the world's bound)")
        if self.staged != (self.stage_decel_mps2 > 0) or self.stage_s < 0 or (
                self.stage_decel_mps2 >= self.decel_mps2):
            raise ValueError("a braking stage needs stage_s > 0 and 0 < stage_decel_mps2 < "
                             f"decel_mps2 (or both 0 for none): {self}")

    @property
    def staged(self) -> bool:
        return self.stage_s > 0

    def to_dict(self) -> dict[str, float]:
        """Its fields; the stage's only when it has one (a record written before stages
        existed reads back as this fallback, and a supervision's key stays the same)."""
        d = asdict(self)
        if not self.staged:
            del d["stage_decel_mps2"], d["stage_s"]
        return d


# Named fallbacks (`evoeye supervise --fallback`). `comfort` is the firm braking of the first
# supervisions (docs/results/supervision-comfort-*), short of the ADS's AEB.
FALLBACKS: dict[str, FallbackConfig] = {
    "production": FallbackConfig(),
    "comfort": FallbackConfig(decel_mps2=6.0, jerk_mps3=10.0),
}
DEFAULT_FALLBACK = "production"


def fallback_with(name: str = DEFAULT_FALLBACK, **changes: float | None) -> FallbackConfig:
    """The named fallback with the `changes` that are not None; ValueError naming the known
    fallbacks, or what is wrong with the result."""
    if name not in FALLBACKS:
        raise ValueError(f"unknown fallback {name!r}; known: {', '.join(FALLBACKS)}")
    return replace(FALLBACKS[name], **{k: v for k, v in changes.items() if v is not None})


@dataclass(frozen=True)
class SupervisorState:
    """What the supervisor saw and did at one frame (channel /supervisor)."""

    t_s: float
    score: float  # the trigger's risk for this frame
    threshold: float  # the alarm threshold this run follows
    above: bool  # score > threshold
    alarm: bool  # above for K consecutive frames, this one included
    mode: str  # MODES: who drives the ego over the next step
    ads_accel_mps2: float  # what the ADS commanded
    accel_cmd_mps2: float  # what was applied
    trigger: str  # the trigger's name, e.g. "fusion", "ttc"
    trigger_version: str


@dataclass
class _Member:
    """One threshold's trigger state: its alarm counter and whether its fallback is engaged."""

    threshold: float
    above_frames: int = 0
    low_frames: int = 0
    engaged: bool = False
    since: int = -1  # the frame of its last engage or release

    def update(self, k: int, score: float, consecutive: int, hold_frames: int) -> None:
        above = score > self.threshold
        self.above_frames = self.above_frames + 1 if above else 0
        if not self.engaged:
            if self.above_frames >= consecutive:
                self.engaged, self.since, self.low_frames = True, k, 0
            return
        self.low_frames = 0 if above else self.low_frames + 1
        if self.low_frames >= hold_frames:
            self.engaged, self.since = False, k

    @property
    def key(self) -> tuple[bool, int]:
        """Equal keys at every frame: the same commands, hence the same run."""
        return self.engaged, self.since


@dataclass(frozen=True)
class Fork:
    """Thresholds that left a simulation at `frame`, their decision there differing from the
    one it follows; they are simulated again as a group of their own."""

    frame: int
    thresholds: tuple[float, ...]


@dataclass(frozen=True)
class Trigger:
    """A monitor as a trigger: its name and version (for the log), the thresholds simulated
    together and K."""

    name: str
    version: str
    thresholds: tuple[float, ...]
    consecutive: int = 1

    def __post_init__(self) -> None:
        if not self.thresholds:
            raise ValueError("a trigger needs at least one threshold")
        if self.consecutive < 1:
            raise ValueError(f"consecutive frames K must be at least 1, got {self.consecutive}")


@dataclass
class SupervisedDriver:
    """The ADS, a risk callable and the fallback, for a group of thresholds (module doc).
    Follows `trigger.thresholds[0]`; `states` holds one SupervisorState per frame stepped."""

    ads: ADS
    risk: Risk
    trigger: Trigger
    config: FallbackConfig
    dt_s: float
    states: list[SupervisorState] = field(default_factory=list)
    forks: list[Fork] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._members = [_Member(t) for t in self.trigger.thresholds]
        self._hold_frames = max(1, round(self.config.hold_s / self.dt_s))
        self._applied_mps2 = 0.0  # the acceleration applied over the last step
        self._ramp_from_mps2 = 0.0  # where the braking ramp starts
        self._onset_frames = round(self.config.onset_s / self.dt_s)
        self._stage_frames = round(self.config.stage_s / self.dt_s)
        self._k = 0

    @property
    def thresholds(self) -> tuple[float, ...]:
        """The thresholds this simulation still stands for."""
        return tuple(m.threshold for m in self._members)

    def step(self, scene: SceneState) -> FrameMessages:
        k, msgs = self._k, self.ads.step(scene)
        self._k += 1
        score = float(self.risk(msgs))
        for m in self._members:
            m.update(k, score, self.trigger.consecutive, self._hold_frames)
        lead = self._members[0]
        stay = [m for m in self._members if m.key == lead.key]
        if len(stay) < len(self._members):
            self.forks.append(Fork(k, tuple(m.threshold for m in self._members
                                            if m.key != lead.key)))
            self._members = stay
        ads_mps2 = float(msgs.control.accel_cmd_mps2)
        mode, accel = self._command(k, lead, ads_mps2, float(scene.speed_mps[0]))
        if accel != ads_mps2:
            cmd = msgs.control
            limit = self.ads.config.control
            # brake 1 is the ADS's full brake (accel_min_mps2, 8 m/s²); the fallback may brake
            # harder, up to the tyres' limit: accel_cmd_mps2 is what the world applies
            brake = min(min(accel, 0.0) / limit.accel_min_mps2, 1.0)
            msgs.control = ControlCommand(
                t_s=cmd.t_s, throttle=max(accel, 0.0) / limit.accel_max_mps2, brake=brake,
                steering_rad=cmd.steering_rad, accel_cmd_mps2=accel)
        self._applied_mps2 = accel
        self.states.append(SupervisorState(
            scene.t_s, score, lead.threshold, score > lead.threshold,
            lead.above_frames >= self.trigger.consecutive, mode, ads_mps2, accel,
            self.trigger.name, self.trigger.version))
        return msgs

    def _command(self, k: int, lead: _Member, ads_mps2: float, speed_mps: float
                 ) -> tuple[str, float]:
        """(mode, acceleration to apply) for frame k."""
        c, dt = self.config, self.dt_s
        if not lead.engaged:
            was = self.states[-1].mode if self.states else "nominal"
            rise = self._applied_mps2 + c.jerk_mps3 * dt
            if was != "nominal" and ads_mps2 > rise:
                return "handback", rise
            return "nominal", ads_mps2
        ramp_frame = k - lead.since - self._onset_frames  # 0 at the ramp's first frame
        if ramp_frame < 0:  # the brakes' dead time: the ADS's command still acts
            return "braking", ads_mps2
        if ramp_frame == 0:
            self._ramp_from_mps2 = min(self._applied_mps2, 0.0)
        if speed_mps <= c.standstill_mps:
            return "holding", -max(speed_mps, 0.0) / dt
        ramp = self._ramp(ramp_frame)
        return "braking", max(min(ramp, ads_mps2), -speed_mps / dt)

    def _ramp(self, n: int) -> float:
        """The fallback's own acceleration n frames into its ramp: down at the jerk limit from
        where it started to decel_mps2, pausing at the stage's deceleration if it has one (or
        where it started, if that was harder) until the stage is over."""
        c, dt, a0 = self.config, self.dt_s, self._ramp_from_mps2
        if c.staged:
            stage = min(-c.stage_decel_mps2, a0)
            if n < self._stage_frames:
                return max(a0 - c.jerk_mps3 * (n + 1) * dt, stage)
            a0 = max(a0 - c.jerk_mps3 * self._stage_frames * dt, stage)
            n -= self._stage_frames
        return max(a0 - c.jerk_mps3 * (n + 1) * dt, -c.decel_mps2)


def supervised(risk: Risk, trigger: Trigger, config: FallbackConfig,
               drivers: list[SupervisedDriver]) -> DriverFactory:
    """A `run_episode` driver factory: the ADS built as usual, wrapped in a SupervisedDriver
    (appended to `drivers`, so the caller can read its states and forks afterwards)."""
    def factory(road_map: RoadMap, rng: np.random.Generator,
                ads_config: ADSConfig) -> SupervisedDriver:
        driver = SupervisedDriver(default_driver(road_map, rng, ads_config), risk, trigger,
                                  config, ads_config.frame_dt_s)
        drivers.append(driver)
        return driver
    return factory


def first_engagements(scores: Sequence[float], thresholds: Sequence[float],
                      consecutive: int = 1) -> list[int | None]:
    """Per threshold, the frame of the first alarm (K consecutive scores above it) in a run
    scoring `scores`, None if none: where its supervised run leaves the unsupervised one."""
    s = np.asarray(scores, dtype=np.float64)
    out: list[int | None] = []
    for t in thresholds:
        above = (s > t).astype(np.int64)
        if consecutive > 1:  # frames above among the last K
            above = np.convolve(above, np.ones(consecutive, np.int64))[: len(s)]
        hits = np.flatnonzero(above >= consecutive)
        out.append(int(hits[0]) if hits.size else None)
    return out


@dataclass(frozen=True)
class SupervisedRun:
    """One supervised simulation: the run, the supervisor's state per frame, the thresholds it
    stands for and the groups that forked off it."""

    episode: Episode
    states: tuple[SupervisorState, ...]  # one per frame of the episode
    thresholds: tuple[float, ...]
    forks: tuple[Fork, ...]


def run_supervised(spec: RunSpec, risk: Risk, trigger: Trigger,
                   config: FallbackConfig = FallbackConfig(),  # noqa: B008 (frozen dataclass)
                   sim: SimConfig | None = None,
                   ads_config: ADSConfig | None = None) -> SupervisedRun:
    """Simulate `spec` with the supervisor following trigger.thresholds[0]; `risk` must be
    fresh (it is called once per frame from the run's first)."""
    drivers: list[SupervisedDriver] = []
    episode = run_episode(spec, sim, ads_config, driver=supervised(risk, trigger, config, drivers))
    if not drivers:  # the world could not be built: no frame was driven
        return SupervisedRun(episode, (), trigger.thresholds, ())
    (d,) = drivers
    return SupervisedRun(episode, tuple(d.states[: len(episode.frames)]), d.thresholds,
                         tuple(d.forks))
