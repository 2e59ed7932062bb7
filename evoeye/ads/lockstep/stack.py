"""One frame of the ADS for every run of a lockstep batch: `step_batch`.

The stages run in the stack's order (`evoeye.ads.stack.ADS.step`), each once for the whole
batch: localization per run (a few scalar draws), sensing, tracking, prediction and planning as
array programs over every run (`sensing`, `tracking`, `prediction`, `planning` in this
package; what is ragged or scalar in them stays per run), control per run (scalar). Every run
gets the messages its own `ADS.step` would give it, bit for bit.

A run whose stage raises ends there (its entry in the result is the exception) and the other
runs go on: a batched stage that raises is redone run by run from the state it started from
(the batched stages change no run's state unless they succeed, and the random streams sensing
drew from are rewound), so only the run that raises is affected.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from evoeye.ads.lockstep.planning import plan_batch
from evoeye.ads.lockstep.prediction import predict_batch
from evoeye.ads.lockstep.sensing import detect_batch
from evoeye.ads.lockstep.tracking import track_batch
from evoeye.ads.messages import FrameMessages
from evoeye.ads.stack import ADS
from evoeye.scene import SceneState

T = TypeVar("T")


def _per_run(fn: Callable[..., T], args: Sequence[tuple]) -> list[T | Exception]:
    out: list[T | Exception] = []
    for a in args:
        try:
            out.append(fn(*a))
        except Exception as exc:  # noqa: BLE001 - one run's error ends that run only
            out.append(exc)
    return out


def _stage(batched: Callable[..., list[T]], per_run: Callable[..., T], args: Sequence[tuple],
           rewind: Callable[[], None] | None = None) -> list[T | Exception]:
    """The stage for every run at once; if that raises, once per run (after `rewind`)."""
    if not args:
        return []
    try:
        return batched(*zip(*args, strict=True))
    except Exception:  # noqa: BLE001 - find the run that raises, keep the others
        if rewind is not None:
            rewind()
        return _per_run(per_run, args)


def step_batch(stacks: Sequence[ADS],
               scenes: Sequence[SceneState]) -> list[FrameMessages | Exception]:
    """Every run's FrameMessages for its scene (or the exception that ended it)."""
    out: list[Any] = [None] * len(stacks)
    rows = list(range(len(stacks)))  # the runs still going this frame

    def done(results: list) -> dict[int, Any]:
        """Each going run's result; a run whose stage raised stops here with its exception."""
        nonlocal rows
        kept = {}
        for i, r in zip(rows, results, strict=True):
            if isinstance(r, Exception):
                out[i] = r
            else:
                kept[i] = r
        rows = list(kept)
        return kept

    ego = done(_per_run(lambda a, s: a.localizer.localize(s),
                        [(stacks[i], scenes[i]) for i in rows]))
    sensors = [stacks[i].perception.sensor for i in rows]
    states = [m.rng.bit_generator.state for m in sensors]

    def rewind() -> None:
        for m, st in zip(sensors, states, strict=True):
            m.rng.bit_generator.state = st

    det = done(_stage(detect_batch, lambda m, s, e: m.detect(s, e),
                      [(stacks[i].perception.sensor, scenes[i], ego[i]) for i in rows], rewind))
    obs = done(_stage(track_batch, lambda p, s, d: p.track(s, d),
                      [(stacks[i].perception, scenes[i], det[i]) for i in rows]))
    pred = done(_stage(predict_batch, lambda p, o, e: p.predict(o, e),
                       [(stacks[i].predictor, obs[i], ego[i]) for i in rows]))
    plan = done(_stage(plan_batch, lambda p, pr, e: p.plan(pr, e),
                       [(stacks[i].planner, pred[i], ego[i]) for i in rows]))
    control = done(_per_run(lambda c, p, e: c.control(p, e),
                            [(stacks[i].controller, plan[i], ego[i]) for i in rows]))
    for i in rows:
        out[i] = FrameMessages(ego[i], obs[i], pred[i], plan[i], control[i])
    return out
