"""An Episode: everything one simulated run produced, in memory (the scenario record D(x))."""

from __future__ import annotations

from dataclasses import dataclass, field

from evoeye.ads.messages import FrameMessages
from evoeye.scene import RoadMap, SceneState

STATUS_OK = "ok"
STATUS_FAILED = "failed"


@dataclass(frozen=True)
class RunSpec:
    """What to run: a concrete scenario, its seed, and where it came from."""

    scenario: str  # logical scenario name
    params: tuple[float, ...]  # the concrete scenario vector, in parameter order
    seed: int
    scenario_id: str
    batch: str = "default"
    source: str = "initial"  # how it was acquired: initial / uniform / evoeye / avfuzzer / …
    round: int = 0
    ads: str = "default"  # the ADS profile that drives the ego (evoeye.ads.profiles)
    world: str = "default"  # the world variant (evoeye.sim.worlds)


@dataclass(frozen=True)
class Outcome:
    """How the run ended. `collision_time_s` is the first frame time with an ego collision."""

    status: str  # STATUS_OK or STATUS_FAILED
    reason: str = ""  # why it failed; empty when ok
    collided: bool = False
    collision_time_s: float | None = None
    other_actor: int | None = None
    duration_s: float = 0.0
    min_distance_m: float | None = None  # min ego–actor footprint distance over the run


@dataclass(frozen=True)
class Frame:
    """One 20 Hz frame: the ground truth O_t and the ADS messages m_t computed from it."""

    scene: SceneState
    messages: FrameMessages


@dataclass
class Episode:
    spec: RunSpec
    road_map: RoadMap
    outcome: Outcome
    software_version: str
    rate_hz: float
    frames: list[Frame] = field(default_factory=list)
