"""The world of many runs stepped in lockstep: B worlds of one logical scenario, one step each.

`World.step` on ~8 actors spends most of its time in numpy calls on tiny arrays, each costing
its call overhead. Here the array phases (reading the state, the pairwise `Relations`, the
leaders, the blocked times, the contact checks) run once for the whole batch in a (B, n) /
(B, n, n) layout, while the phases that are scalar Python per vehicle (the NPC driver models and
scripts, the crossings, the arc checks of turning NPCs, highway-env's ego step) run per world
through the very `World` methods its own `step` calls.

Every world ends in exactly the state its own `step` leaves (every float bit): the batched
phases are elementwise ufuncs, which give the same bits per element whatever the array around
it, and reductions (the leader's `min` / `argmin` over a row) keep each world's row as its own
axis of the same length n, in the same order. Worlds of a batch with different actor counts
(the `follower` variant adds one) are stepped as separate groups. Worlds are independent: no
world reads another's state, so the phases may interleave across worlds.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from evoeye.boxes import box_corners, box_gap_bound, box_gaps
from evoeye.scene import SceneState
from evoeye.sim.traffic import (
    ALIGNED_COS,
    BLOCKING_M,
    CORRIDOR_MARGIN_M,
    LOOKAHEAD_M,
    Relations,
    not_self,
)
from evoeye.sim.world import CONTACT_SLACK_M, World, answer_blocks

__all__ = ["scenes", "step_worlds"]

# a group smaller than this is stepped (and read) by its worlds' own methods: for one world the
# batch's stacking costs more than it saves (the result is the same either way)
MIN_BATCH = 2


def _groups(worlds: Sequence[World]) -> list[list[int]]:
    """Indices of the worlds, grouped by actor count (each group in the given order)."""
    groups: dict[int, list[int]] = {}
    for b, w in enumerate(worlds):
        groups.setdefault(len(w.vehicles), []).append(b)
    return list(groups.values())


def _states(worlds: Sequence[World]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(B, n) x, y, heading, speed: `World._state` of every world, one row each."""
    vs = [v for w in worlds for v in w.vehicles]
    shape = (len(worlds), -1)
    xy = np.concatenate([v.position for v in vs]).reshape(len(worlds), -1, 2)
    heading = np.array([v.heading for v in vs], dtype=float).reshape(shape)
    speed = np.array([v.speed for v in vs], dtype=float).reshape(shape)
    return xy[..., 0].copy(), xy[..., 1].copy(), heading, speed


def scenes(worlds: Sequence[World]) -> list[SceneState]:
    """`[w.scene() for w in worlds]`, with the state read once per group of worlds."""
    out: list[SceneState | None] = [None] * len(worlds)
    for group in _groups(worlds):
        if len(group) < MIN_BATCH:
            for b in group:
                out[b] = worlds[b].scene()
            continue
        ws = [worlds[b] for b in group]
        x, y, heading, speed = _states(ws)
        accel = np.stack([w._accel for w in ws])  # fresh rows: the scene's own, as `.copy()`
        length = np.stack([w.length_m for w in ws])
        width = np.stack([w.width_m for w in ws])
        crashed = np.stack([w.crashed for w in ws])
        actor_id = np.stack([w.actor_id for w in ws])
        for k, (b, w) in enumerate(zip(group, ws, strict=True)):
            out[b] = SceneState(
                t_s=w.t_s, actor_id=actor_id[k], x_m=x[k], y_m=y[k], heading_rad=heading[k],
                speed_mps=speed[k], accel_mps2=accel[k], length_m=length[k], width_m=width[k],
                crashed=crashed[k], ego_collision=bool(w.crashed[0]),
                collision_actor=w.collision_actor, occluders=w.occluders,
            )
    return out


def step_worlds(worlds: Sequence[World], accels: Sequence[float], steers: Sequence[float],
                dt: float) -> list[Exception | None]:
    """`w.step(a, s, dt)` for every world and its ego command, the array work done once per
    group of worlds with the same actor count. Per world, the exception its own phases raised
    (None: stepped); that world is left part-stepped and steps no further, the others go on. An
    error in the array work, which no world's values cause (NaN does not raise), raises."""
    if not len(worlds) == len(accels) == len(steers):
        raise ValueError(f"{len(worlds)} worlds, {len(accels)} accels, {len(steers)} steers")
    errors: list[Exception | None] = [None] * len(worlds)
    for group in _groups(worlds):
        if len(group) < MIN_BATCH:
            for b in group:
                try:
                    worlds[b].step(accels[b], steers[b], dt)
                except Exception as exc:  # noqa: BLE001 - this world's error, the others go on
                    errors[b] = exc
            continue
        failed = _step_group([worlds[b] for b in group], [accels[b] for b in group],
                             [steers[b] for b in group], dt)
        for k, exc in failed.items():
            errors[group[k]] = exc
    return errors


def _relations(x: np.ndarray, y: np.ndarray, heading: np.ndarray, speed: np.ndarray,
               half_l: np.ndarray, half_w: np.ndarray) -> Relations:
    """`Relations.of` for (B, n) states: (B, n, n) arrays, row i of world b seen from i."""
    dx = x[:, None, :] - x[:, :, None]
    dy = y[:, None, :] - y[:, :, None]
    c, s = np.cos(heading)[:, :, None], np.sin(heading)[:, :, None]
    xi = c * dx + s * dy
    eta = c * dy - s * dx
    return Relations(
        xi=xi, eta=eta, cos_dh=np.cos(heading[:, None, :] - heading[:, :, None]),
        bumper=np.abs(xi) - half_l, half_w=half_w, speed=speed,
    )


def _leaders(rel: Relations, shift_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`traffic.leaders` for (B, n, n) relations: (B, n) gap, leader speed, blocking gap. A
    world with no lane change under way gets no target-lane term (its shift row is 0, so the
    term adds nothing), as its own call skips it."""
    n = rel.speed.shape[1]
    reach = rel.half_w + CORRIDOR_MARGIN_M
    in_lane = np.abs(rel.eta) < reach
    if np.count_nonzero(shift_m):
        in_lane |= (shift_m != 0.0)[:, :, None] & (np.abs(rel.eta - shift_m[:, :, None]) < reach)
    ahead = (rel.xi > 0.0) & not_self(n) & in_lane
    aligned = rel.cos_dh > ALIGNED_COS
    gap = np.where(ahead & aligned & (rel.xi < LOOKAHEAD_M), rel.bumper, np.inf)
    block = np.where(ahead & ~aligned & (rel.xi < BLOCKING_M), rel.bumper, np.inf).min(axis=2)
    j = gap.argmin(axis=2)[:, :, None]  # (B, n, 1)
    best = np.take_along_axis(gap, j, axis=2)[:, :, 0]
    v_lead = np.take_along_axis(rel.speed, j[:, :, 0], axis=1) * np.take_along_axis(
        rel.cos_dh, j, axis=2)[:, :, 0]
    return best, np.where(np.isfinite(best), v_lead, 0.0), block


def _step_group(ws: list[World], accels: list[float], steers: list[float],
                dt: float) -> dict[int, Exception]:
    """`World.step`'s phases for worlds with the same actor count, in its order per world; the
    exceptions of the worlds whose own phases raised (by index in `ws`)."""
    x, y, heading, speed = _states(ws)
    rel = _relations(x, y, heading, speed, np.stack([w._half_sums[0] for w in ws]),
                     np.stack([w._half_sums[1] for w in ws]))
    gap, v_lead, block = _leaders(rel, np.array([w._lateral_targets() for w in ws]))
    failed: dict[int, Exception] = {}

    def each(phase: Callable[[int, World], None]) -> None:
        for k, w in enumerate(ws):
            if k not in failed:
                try:
                    phase(k, w)
                except Exception as exc:  # noqa: BLE001 - this world's error only
                    failed[k] = exc

    def arcs(k: int, w: World) -> None:
        if w._on_curves:  # writes into its row of block
            w._block_along_paths(block[k], x[k], y[k], heading[k])

    each(arcs)
    gap, v_lead, blocked_s = answer_blocks(gap, v_lead, block,
                                           np.stack([w._blocked_s for w in ws]), dt)

    def waits(k: int, w: World) -> None:
        w._blocked_s = blocked_s[k]
        w._wait_at_crossings(gap[k], v_lead[k])  # writes into its rows of gap, v_lead
        if w._scripted:
            w._lane_changes(Relations(
                xi=rel.xi[k], eta=rel.eta[k], cos_dh=rel.cos_dh[k], bumper=rel.bumper[k],
                half_w=rel.half_w[k], speed=rel.speed[k]), speed[k])

    each(waits)
    gaps, v_leads = gap.tolist(), v_lead.tolist()

    def moves(k: int, w: World) -> None:
        w._accel = np.array(w._advance(accels[k], steers[k], w._decide(gaps[k], v_leads[k], dt),
                                       dt))

    each(moves)
    _contacts([w for k, w in enumerate(ws) if k not in failed])
    return failed


def _contacts(ws: list[World]) -> None:
    """`World._contacts` for worlds with the same actor count: the circle test, the bound and
    the exact gap on the pairs of every world at once, then each world marks its own. The exact
    gap's reductions (einsum, matmul) run over each pair's own corners, so a pair's gap does not
    depend on which other pairs share the call (tests/sim/test_lockstep_world.py checks it)."""
    if not ws:
        return
    x, y, heading, _ = _states(ws)
    i, j = ws[0]._pair_i, ws[0]._pair_j  # (P,) the same pairs for every n
    close = np.hypot(x[:, i] - x[:, j], y[:, i] - y[:, j]) <= np.stack(
        [w._pair_reach_m for w in ws])  # (B, P)
    b, p = np.nonzero(close)  # world by world, each in its pair order
    if not len(b):
        return
    i, j = i[p], j[p]
    length, width = np.stack([w.length_m for w in ws]), np.stack([w.width_m for w in ws])
    bound = box_gap_bound(x[b, i], y[b, i], heading[b, i], length[b, i], width[b, i], x[b, j],
                          y[b, j], heading[b, j], length[b, j], width[b, j])
    near = bound <= CONTACT_SLACK_M
    if not np.count_nonzero(near):
        return
    b, i, j = b[near], i[near], j[near]
    touching = box_gaps(
        box_corners(x[b, i], y[b, i], heading[b, i], length[b, i], width[b, i]),
        box_corners(x[b, j], y[b, j], heading[b, j], length[b, j], width[b, j])) <= 0.0
    if not np.count_nonzero(touching):
        return
    b, i, j = b[touching], i[touching], j[touching]
    for k in np.unique(b).tolist():
        mine = b == k
        ws[k]._crash(i[mine], j[mine], x[k], y[k])
