"""One run of a batch under every trigger and threshold of a supervision: its record.

1. The scoring pass: the unsupervised run, re-simulated with every trigger scoring each frame
   beside the ADS (`ObservedDriver`; the ADS drives unchanged). Its outcome must equal the
   logged one (determinism: a run that does not reproduce is an error, not data).
2. Per trigger and threshold, the first alarm before the unsupervised collision
   (`first_engagements`). A threshold without one drives the unsupervised run: nothing to
   simulate. The others are simulated, all of a trigger's in one group (`run_supervised`):
   the simulation follows the group's first threshold, and the thresholds whose decision
   differs at some frame fork off and are simulated again from scratch as a group of their
   own, so thresholds that agree on every engage and release share one simulation.
3. Each simulation is checked to be the unsupervised run up to its first alarm: the same scores
   at every frame before it and the alarm at the frame the scoring pass found.

An intervention (an engagement of the fallback) is judged against the unsupervised run at its
frame: *late* at or after the unsupervised collision (it counts as nothing); *true* when the
frame is labelled 1 (a collision within H, Definition 1); *justified* when labelled 0 but the
unsupervised run comes critically close within H (`criticality`: ground-truth TTC < 1.5 s or a
required deceleration > 4 m/s²); otherwise *unneeded*. An unneeded intervention is *false* only
if it changed the applied command at some frame of its engagement — one that rode along with
the ADS's own harder braking changed nothing a passenger could feel. The earlier definition —
every intervention at a frame labelled 0, a *false alarm* — is recorded beside it
(`false_alarms`). A later intervention is judged against the unsupervised run at the same time:
after the first one the supervised world has diverged, and what would have happened without
supervision is the only reference all triggers share.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from evoeye.atomic import atomic_file
from evoeye.criticality import (
    Criticality,
    frame_risk,
    justified_frames,
    safe_encounters,
)
from evoeye.evaluation.mechanism import mechanism
from evoeye.evaluation.supervision.settings import Settings
from evoeye.evaluation.supervision.triggers import FRAME_S, TriggerSpec, load_monitor
from evoeye.log.writer import Supervision, write_episode
from evoeye.monitor.online import FrameInputs, OnlineScorer, online_scorer
from evoeye.paths import DataRoot
from evoeye.scene import SceneState
from evoeye.sim.counterfactual import struck_from_behind
from evoeye.sim.episode import STATUS_OK, Episode, RunSpec
from evoeye.sim.runner import DriverFactory, default_driver, run_episode
from evoeye.sim.supervisor import SupervisedRun, Trigger, first_engagements, run_supervised
from evoeye.store.labels import eligible_frames, frame_labels

FALLBACK_MODES = ("braking", "holding")  # an intervention: the fallback drives the ego
# the jerk of a step into the final stop is left out: a stop's own, the same for any stop (the
# ADS's too: braking that no longer finds speed to take off)
STOPPING_MPS = 0.5
# this thread's scorers, by (root, scenario, splits, source, ref): a scorer streams one run, so
# two runs supervised at once in threads of one process (Prefect's default task runner) each
# need their own; sharing one interleaved their frames and broke the pairing
_LOCAL = threading.local()


class ReproductionError(RuntimeError):
    """A run does not reproduce: its re-simulation differs from its log, or a supervised run
    differs from the unsupervised one before its first alarm."""


@dataclass(frozen=True)
class RunJob:
    """One run to supervise: its spec, the outcome its log records, where the results go."""

    root: str
    folder: str  # the supervision's folder
    settings: Settings
    spec: RunSpec
    logged: dict  # the log's run metadata (status, collided, collision_time_s)


class OracleScorer:
    """The oracle trigger's score (`triggers.oracle_trigger`): minus the seconds left to the
    unsupervised run's collision, in whole frames; −inf in a run without one."""

    def __init__(self, collision_time_s: float | None) -> None:
        self.collision_frame = (None if collision_time_s is None
                                else round(collision_time_s / FRAME_S))
        self._k = 0

    def reset(self) -> None:
        self._k = 0

    def score(self, frame: FrameInputs) -> float:
        k, self._k = self._k, self._k + 1
        if self.collision_frame is None:
            return float("-inf")
        return -(self.collision_frame - k) * FRAME_S


def scorer(root: DataRoot, settings: Settings, trigger: TriggerSpec,
           job: RunJob | None = None) -> OnlineScorer:
    """The trigger's online scorer, loaded once per thread and reset (the oracle's: built for
    `job`'s run, from the collision its log records)."""
    if trigger.oracle:
        if job is None:
            raise ValueError("the oracle scores a known run: give its job")
        return OracleScorer(job.logged.get("collision_time_s"))
    key = (str(root.path), settings.scenario, settings.splits, trigger.source, trigger.ref)
    cache: dict[tuple, OnlineScorer] = _LOCAL.__dict__.setdefault("scorers", {})
    if key not in cache:
        monitor = load_monitor(root, settings.scenario, settings.splits, trigger.source,
                               trigger.ref)
        if monitor.version != trigger.version:
            raise ReproductionError(f"trigger {trigger.name} loads as {monitor.version}, "
                                    f"calibrated as {trigger.version}")
        cache[key] = online_scorer(monitor)
    found = cache[key]
    found.reset()
    return found


class ObservedDriver:
    """The ADS driving unchanged, every scorer scoring each frame (the scoring pass)."""

    def __init__(self, ads, scorers: list[OnlineScorer]) -> None:
        self.ads = ads
        self.scorers = scorers
        self.scores: list[list[float]] = [[] for _ in scorers]

    def step(self, scene: SceneState):
        msgs = self.ads.step(scene)
        inputs = FrameInputs.of(msgs)
        for out, s in zip(self.scores, self.scorers, strict=True):
            out.append(s.score(inputs))
        return msgs


def observed(scorers: list[OnlineScorer], drivers: list[ObservedDriver]) -> DriverFactory:
    def factory(road_map, rng, ads_config) -> ObservedDriver:
        drivers.append(ObservedDriver(default_driver(road_map, rng, ads_config), scorers))
        return drivers[-1]
    return factory


@dataclass(frozen=True)
class Reference:
    """The unsupervised run as the judge of interventions."""

    eligible: int  # frames before its collision (all, without one)
    label: np.ndarray  # (eligible,) int8, y_t with horizon H
    justified: np.ndarray  # (eligible,) bool: an intervention there is justified (module doc)
    collision_time_s: float | None
    dt_s: float
    safe_encounters: int = 0  # hazardous encounters that ended safely (`criticality`)

    @classmethod
    def of(cls, episode: Episode, horizon_s: float,
           criticality: Criticality = Criticality()) -> Reference:  # noqa: B008 (frozen)
        t = np.array([f.scene.t_s for f in episode.frames])
        hit = np.array([f.scene.ego_collision for f in episode.frames], dtype=bool)
        keep = eligible_frames(t, hit)
        label = frame_labels(t, hit, horizon_s)[keep]
        risk = frame_risk([f.scene for f in episode.frames[: int(keep.sum())]])  # eligible
        dt_s = 1.0 / episode.rate_hz
        justified = justified_frames(label, risk.critical(criticality),
                                     int(round(horizon_s / dt_s)))
        return cls(int(keep.sum()), label, justified, episode.outcome.collision_time_s, dt_s,
                   safe_encounters(risk.conflict(criticality), justified))

    @property
    def safe_s(self) -> float:
        """Seconds of safe driving by the label: eligible frames labelled 0."""
        return float((self.label == 0).sum()) * self.dt_s

    @property
    def calm_s(self) -> float:
        """Seconds of safe driving: eligible frames where an intervention is not justified."""
        return float((~self.justified).sum()) * self.dt_s

    def judge(self, frame: int) -> str:
        """'late', 'true', 'justified' or 'unneeded' for an intervention at `frame`."""
        if frame >= self.eligible:
            return "late"
        if self.label[frame]:
            return "true"
        return "justified" if self.justified[frame] else "unneeded"


def _changed_command(states, start: int) -> bool:
    """Whether the engagement starting at `start` applied, at some frame before control went
    back to the ADS, another acceleration than the ADS commanded."""
    for s in states[start:]:
        if s.mode == "nominal":
            return False
        if s.accel_cmd_mps2 != s.ads_accel_mps2:
            return True
    return False


def summarise(run: SupervisedRun, ref: Reference) -> dict:
    """What one (finished) supervised simulation cost and achieved, before its own collision
    if it has one."""
    ep, states, dt_s = run.episode, run.states, ref.dt_s
    o = ep.outcome
    end = len(states)
    if o.collided:
        end = min(end, int(round(o.collision_time_s / dt_s)))
    modes = [s.mode for s in states[:end]]
    starts = [k for k, m in enumerate(modes) if m in FALLBACK_MODES
              and (k == 0 or modes[k - 1] not in FALLBACK_MODES)]
    verdicts = [ref.judge(k) for k in starts]
    changed = [_changed_command(states[:end], k) for k in starts]
    false = sum(v == "unneeded" and c for v, c in zip(verdicts, changed, strict=True))
    acting = np.array([m != "nominal" for m in modes], dtype=bool)  # (F,)
    accel = np.array([s.accel_cmd_mps2 for s in states[:end]])
    speed = np.array([f.scene.speed_mps[0] for f in ep.frames[:end]])
    jerk = np.abs(np.diff(accel)) / dt_s if end > 1 else np.zeros(0)  # (F-1,) step k-1 → k
    near = (acting[1:] | acting[:-1]) & (speed[1:] > STOPPING_MPS) if end > 1 \
        else np.zeros(0, bool)
    first_lead = (ref.collision_time_s - starts[0] * dt_s
                  if starts and verdicts[0] == "true" else None)
    return {
        "collided": o.collided, "collision_time_s": o.collision_time_s,
        "other_actor": o.other_actor, "struck_from_behind": struck_from_behind(ep),
        "duration_s": o.duration_s, "min_distance_m": o.min_distance_m,
        "interventions": len(starts), "false_interventions": false,
        "false_alarms": verdicts.count("justified") + verdicts.count("unneeded"),
        "justified_interventions": verdicts.count("justified"),
        "idle_interventions": verdicts.count("unneeded") - false,
        "true_interventions": verdicts.count("true"), "first_lead_s": first_lead,
        "fallback_s": float(acting.sum()) * dt_s,
        "peak_decel_mps2": float(max(0.0, -accel[acting].min())) if acting.any() else 0.0,
        "peak_jerk_mps3": float(jerk[near].max()) if near.any() else 0.0,
    }


def _check_prefix(run: SupervisedRun, scores: list[float], first: int, name: str) -> None:
    """The supervised run is the unsupervised one until its first alarm (module doc)."""
    seen = [s.score for s in run.states[: first + 1]]
    if seen != scores[: first + 1]:
        k = next(i for i, (a, b) in enumerate(zip(seen, scores, strict=False)) if a != b)
        raise ReproductionError(f"{name}: the supervised run scores {seen[k]!r} at frame {k}, "
                                f"the unsupervised {scores[k]!r}: runs must agree until the "
                                f"first alarm (frame {first})")
    engaged = next((k for k, s in enumerate(run.states) if s.mode in FALLBACK_MODES), None)
    if engaged != first:
        raise ReproductionError(f"{name}: first alarm at frame {engaged}, expected {first}")


def sweep_trigger(job: RunJob, trigger: TriggerSpec, scores: list[float],
                  ref: Reference) -> dict:
    """Every threshold of one trigger on one run: which simulation each drives, and those."""
    s = job.settings
    cut = scores[: ref.eligible]  # an alarm at or after the collision changes nothing before it
    first = first_engagements(cut, trigger.thresholds, s.consecutive)
    index = {t: i for i, t in enumerate(trigger.thresholds)}
    sim_of: list[int | None] = [None] * len(first)
    sims: list[dict] = []
    alarmed = tuple(t for t, f in zip(trigger.thresholds, first, strict=True) if f is not None)
    pending = [alarmed] if alarmed else []
    while pending:
        group = pending.pop(0)
        lead = index[group[0]]
        risk_scorer = scorer(DataRoot.resolve(job.root), s, trigger, job)
        run = run_supervised(job.spec, lambda m, sc=risk_scorer: sc.score(FrameInputs.of(m)),
                             Trigger(trigger.name, trigger.version, group, s.consecutive),
                             s.fallback)
        name = f"{job.spec.scenario_id} {trigger.name}"
        if run.episode.outcome.status != STATUS_OK:  # a broken run is no outcome to count
            raise RuntimeError(f"{name}: the supervised run failed: {run.episode.outcome.reason}")
        _check_prefix(run, scores, first[lead], name)
        pending += [f.thresholds for f in run.forks]
        summary = summarise(run, ref)
        summary |= {"lead": lead, "first_alarm_frame": first[lead],
                    "thresholds": [index[t] for t in run.thresholds],
                    "log": _log(job, trigger, run, lead, summary["collided"])}
        for t in run.thresholds:
            sim_of[index[t]] = len(sims)
        sims.append(summary)
    return {"version": trigger.version, "first_alarm_frame": first, "sim_of": sim_of,
            "sims": sims}


def supervised_spec(spec: RunSpec, trigger: str, lead: int) -> RunSpec:
    """How a supervised run's log names itself: its own scenario id (the run's, suffixed with
    the trigger and its leading threshold) and source, in batch `<batch>-supervised`, so it is
    never mistaken for, nor ingested as a duplicate of, the unsupervised run."""
    return replace(spec, scenario_id=f"{spec.scenario_id}.{trigger}.t{lead:02d}",
                   batch=f"{spec.batch}-supervised", source="supervised")


def _log(job: RunJob, trigger: TriggerSpec, run: SupervisedRun, lead: int,
         collided: bool) -> str | None:
    """Write the simulation's log if the policy asks for it: under the supervision's folder,
    or (`logs_into_runs`) where `evoeye ingest` finds it. Its path under the data root."""
    s = job.settings
    if s.logs == "none" or (s.logs == "collided" and not collided):
        return None
    root = DataRoot.resolve(job.root)
    spec = supervised_spec(job.spec, trigger.name, lead)
    path = (root.run_log(spec.scenario, spec.batch, spec.scenario_id) if s.logs_into_runs else
            Path(job.folder) / "logs" / trigger.name / f"{spec.scenario_id}.mcap")
    path.parent.mkdir(parents=True, exist_ok=True)
    record = {"trigger": trigger.name, "trigger_version": trigger.version,
              "thresholds": list(run.thresholds), "consecutive": s.consecutive,
              "fallback": s.to_dict()["fallback"], "unsupervised_id": job.spec.scenario_id}
    write_episode(replace(run.episode, spec=spec), path, Supervision(run.states, record))
    return root.relative(path)


def supervise_run(job: RunJob) -> dict:
    """The run's record (module doc), written to `<folder>/runs/<scenario_id>.json`."""
    import orjson

    root, s = DataRoot.resolve(job.root), job.settings
    scorers = [scorer(root, s, t, job) for t in s.triggers]
    drivers: list[ObservedDriver] = []
    unsupervised = run_episode(job.spec, driver=observed(scorers, drivers))
    o = unsupervised.outcome
    logged = (job.logged.get("status"), job.logged.get("collided"),
              job.logged.get("collision_time_s"))
    if o.status != STATUS_OK and logged[0] == STATUS_OK:
        raise ReproductionError(f"{job.spec.scenario_id} failed when re-simulated under the "
                                f"triggers, not when logged: {o.reason}")
    if (o.status, o.collided, o.collision_time_s) != logged:
        raise ReproductionError(
            f"{job.spec.scenario_id} re-simulates as {(o.status, o.collided, o.collision_time_s)}"
            f", its log says {logged}: was it simulated by another software version?")
    record = {"scenario_id": job.spec.scenario_id, "seed": job.spec.seed,
              "status": o.status, "reason": o.reason}
    if o.status == STATUS_OK:
        ref = Reference.of(unsupervised, s.horizon_s, s.criticality)
        record["unsupervised"] = {
            "collided": o.collided, "collision_time_s": o.collision_time_s,
            "other_actor": o.other_actor, "struck_from_behind": struck_from_behind(unsupervised),
            "duration_s": o.duration_s, "safe_s": ref.safe_s, "calm_s": ref.calm_s,
            "safe_encounters": ref.safe_encounters, "eligible_frames": ref.eligible,
            "mechanism": None if (m := mechanism(unsupervised)) is None else m.to_dict()}
        record["triggers"] = {t.name: sweep_trigger(job, t, scores, ref)
                              for t, scores in zip(s.triggers, drivers[0].scores, strict=True)}
    path = Path(job.folder) / "runs" / f"{job.spec.scenario_id}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_file(path) as f:
        f.write(orjson.dumps(record, option=orjson.OPT_INDENT_2 | orjson.OPT_SORT_KEYS))
    return record
