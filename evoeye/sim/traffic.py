"""What NPC drivers see of each other: pairwise relations in each vehicle's own frame.

All pairs at once: (n, n) arrays, row i = seen from vehicle i. An NPC follows the nearest
vehicle ahead in its corridor that drives its way (its lane, and during a lane change also the
target lane), starts a scripted lane change only into a gap that other NPCs leave it, and where
two NPCs' paths cross (`Conflict`), the one that would arrive later waits for the other. The
ego is not asked: NPCs do not yield to it and a cut-in is aimed at it, which is the point of
the scenarios.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

CORRIDOR_MARGIN_M = 0.5  # lateral slack added to the two half-widths
ALIGNED_COS = 0.5  # a vehicle within ±60° of one's heading drives one's way …
BLOCKING_M = 25.0  # … and any vehicle this close in one's corridor blocks it, whatever its way
LOOKAHEAD_M = 120.0
HALF_LANE_M = 2.0
CLEAR_FRONT_M, CLEAR_FRONT_S = 5.0, 0.5  # a lane change needs this bumper gap ahead …
CLEAR_REAR_M, CLEAR_REAR_S = 5.0, 0.6  # … and behind, each plus 2 s of any closing speed


@dataclass(frozen=True)
class Relations:
    """xi, eta: (n, n) position of j along / to the left of i's heading; cos_dh: heading
    agreement; bumper: (n, n) |xi| minus the two half-lengths."""

    xi: np.ndarray
    eta: np.ndarray
    cos_dh: np.ndarray
    bumper: np.ndarray
    half_w: np.ndarray  # (n, n) sum of half-widths
    speed: np.ndarray  # (n,)

    @classmethod
    def of(cls, x, y, heading, speed, half_l: np.ndarray, half_w: np.ndarray) -> Relations:
        """half_l, half_w: (n, n) the sums of half-lengths and of half-widths (`half_sums`)."""
        dx = x[None, :] - x[:, None]
        dy = y[None, :] - y[:, None]
        c, s = np.cos(heading)[:, None], np.sin(heading)[:, None]
        xi = c * dx + s * dy
        eta = c * dy - s * dx
        return cls(
            xi=xi, eta=eta, cos_dh=np.cos(heading[None, :] - heading[:, None]),
            bumper=np.abs(xi) - half_l, half_w=half_w, speed=speed,
        )

    def gap_ahead_of(self, i: int, j: int) -> float:
        """Bumper gap by which i is ahead of j along i's heading (negative when behind)."""
        return float(self.bumper[i, j] if self.xi[i, j] < 0.0 else -self.bumper[i, j])


def half_sums(length: np.ndarray, width: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, n) sums of the half-lengths and of the half-widths of every pair (fixed per world)."""
    return 0.5 * (length[:, None] + length[None, :]), 0.5 * (width[:, None] + width[None, :])


@functools.cache
def not_self(n: int) -> np.ndarray:
    """(n, n) True off the diagonal (read-only: shared by every call)."""
    mask = ~np.eye(n, dtype=bool)
    mask.flags.writeable = False
    return mask


def leaders(rel: Relations, shift_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(gap, leader speed along one's heading, blocking gap) per vehicle: the nearest vehicle
    ahead in its corridor (or in its target lane, `shift_m` to the side, during a lane change)
    that drives its way; and the nearest one across its way that blocks its corridor within
    `BLOCKING_M` (a crossing car, which a driver answers only after a reaction time). Gaps are
    inf without one. (n,) each."""
    n = len(rel.speed)
    reach = rel.half_w + CORRIDOR_MARGIN_M
    in_lane = np.abs(rel.eta) < reach
    if np.count_nonzero(shift_m):  # someone changes lanes: its target lane counts too
        in_lane |= (shift_m != 0.0)[:, None] & (np.abs(rel.eta - shift_m[:, None]) < reach)
    ahead = (rel.xi > 0.0) & not_self(n) & in_lane
    aligned = rel.cos_dh > ALIGNED_COS
    gap = np.where(ahead & aligned & (rel.xi < LOOKAHEAD_M), rel.bumper, np.inf)
    block = np.where(ahead & ~aligned & (rel.xi < BLOCKING_M), rel.bumper, np.inf).min(axis=1)
    j = gap.argmin(axis=1)
    rows = np.arange(n)
    best = gap[rows, j]
    return best, np.where(np.isfinite(best), rel.speed[j] * rel.cos_dh[rows, j], 0.0), block


CURVE_AHEAD_RAD = 0.1  # a path turning more than this within BLOCKING_M is checked along its arc


def may_curve(path) -> bool:
    """Whether `path_block` can find anything on `path` at all: its heading turns by
    CURVE_AHEAD_RAD somewhere (a straight lane never does, so its NPCs need no arc check)."""
    return float(path.h.max() - path.h.min()) >= CURVE_AHEAD_RAD


def path_block(path, s_m: float, half_len_m: float, half_wid_m: float, x: np.ndarray,
               y: np.ndarray, heading: np.ndarray, half_l: np.ndarray, half_w: np.ndarray,
               me: int) -> float:
    """Bumper gap along a *curved* path to the first vehicle (any row but `me`, the NPC's own)
    whose footprint lies on it within `BLOCKING_M` and that does not drive its way there (a car
    standing in a turn, the ego's nose in the crossing); inf if none, or if the path ahead is
    straight (the straight corridor of `leaders` already covers it). Footprints are exact boxes:
    the distance from every path sample to each box, against the NPC's half-width plus the
    corridor margin."""
    k0 = path.index(s_m)
    k1 = path.index(s_m + half_len_m + BLOCKING_M)
    if k1 <= k0 or path.turn(k0, k1) < CURVE_AHEAD_RAD or len(x) < 2:
        return np.inf
    px, py, ph = path.x[k0:k1 + 1], path.y[k0:k1 + 1], path.h[k0:k1 + 1]  # (K,)
    c, s = np.cos(heading)[:, None], np.sin(heading)[:, None]  # (n, 1)
    dx, dy = px[None, :] - x[:, None], py[None, :] - y[:, None]  # (n, K)
    ex = np.maximum(np.abs(c * dx + s * dy) - half_l[:, None], 0.0)
    ey = np.maximum(np.abs(c * dy - s * dx) - half_w[:, None], 0.0)
    on_path = ex * ex + ey * ey < (half_wid_m + CORRIDOR_MARGIN_M) ** 2  # (n, K)
    on_path[me] = False  # its own box
    on_path[:, : int(half_len_m / path.step_m) + 1] = False  # behind its own front bumper
    if not np.count_nonzero(on_path):  # usually: then the headings need not be compared
        return np.inf
    on_path &= np.cos(heading[:, None] - ph[None, :]) <= ALIGNED_COS  # not a leader
    hit = np.logical_or.reduce(on_path, axis=0)
    if not np.count_nonzero(hit):
        return np.inf
    return max(float(path.s[k0 + int(hit.argmax())] - s_m) - half_len_m, 0.0)


def clear_to_change(rel: Relations, i: int, offset_m: float) -> bool:
    """Whether NPC i may move `offset_m` sideways: no other NPC (the ego is not asked) in the
    target lane within the bumper gaps a careful driver leaves ahead and behind."""
    others = np.ones(len(rel.speed), dtype=bool)
    others[[0, i]] = False  # row 0 is the ego
    in_target = np.abs(rel.eta[i] - offset_m) < HALF_LANE_M
    v_i, v_j = rel.speed[i], rel.speed
    need_front = CLEAR_FRONT_M + CLEAR_FRONT_S * v_i + 2.0 * np.maximum(v_i - v_j, 0.0)
    need_rear = CLEAR_REAR_M + CLEAR_REAR_S * v_j + 2.0 * np.maximum(v_j - v_i, 0.0)
    need = np.where(rel.xi[i] >= 0.0, need_front, need_rear)
    return not np.count_nonzero(others & in_target & (rel.bumper[i] < need))


DECIDE_WITHIN_M = 60.0  # a crossing's order is settled once both NPCs are this close to it
PASSED_M = 6.0  # the first NPC is through once its centre is this far past the crossing point
COMMIT_DECEL_MPS2 = 3.0  # a yielding NPC that could no longer stop at this rate goes on
CLEAR_MARGIN_S = 1.0  # an NPC slows for a crossing NPC that clears less than this before it


@dataclass
class Conflict:
    """NPCs i and j (world rows) whose paths cross at arc lengths s_i and s_j; each waits, if it
    must, with its centre at stop_i / stop_j."""

    i: int
    j: int
    s_i: float
    s_j: float
    stop_i: float
    stop_j: float
    first: int | None = field(default=None)  # the row that goes first, once settled

    def wait_gap(self, s: dict[int, float], v: dict[int, float]) -> tuple[int, float] | None:
        """(row that waits, its distance to its stop point) while the first NPC is not through
        and the other would reach its stop point before the first has cleared the crossing
        (with `CLEAR_MARGIN_S` to spare); None once there is nothing to wait for (or nothing
        settled yet). A driver slows for a crossing car only if their timing calls for it."""
        to_i, to_j = self.s_i - s[self.i], self.s_j - s[self.j]
        if to_i < -PASSED_M or to_j < -PASSED_M:  # one is through: the other may go
            return None
        if self.first is None:
            if max(to_i, to_j) > DECIDE_WITHIN_M:
                return None
            t_i, t_j = to_i / max(v[self.i], 1.0), to_j / max(v[self.j], 1.0)
            self.first = self.i if t_i <= t_j else self.j
        f, to_f, w, stop_w = ((self.i, to_i, self.j, self.stop_j) if self.first == self.i
                              else (self.j, to_j, self.i, self.stop_i))
        to_stop = stop_w - s[w]
        t_clear = (to_f + PASSED_M) / max(v[f], 1.0)
        if to_stop / max(v[w], 1.0) > t_clear + CLEAR_MARGIN_S:
            return None
        return w, to_stop


@dataclass
class YieldToEgo:
    """NPC row i turns across or into the ego's path and yields to it: it goes only if the ego
    would reach the crossing at least `gap_s` after it (an assertive driver's accepted gap),
    otherwise it waits with its centre at stop_i. The gap is judged again every step until the
    NPC is committed: past its stop point, or too fast to stop before it at `COMMIT_DECEL_MPS2`
    (a driver who saw a gap 60 m out still brakes when the ego turns out to arrive sooner)."""

    i: int
    s_i: float  # arc length of the crossing on the NPC's path
    s_ego: float  # … and on the ego's route
    stop_i: float
    gap_s: float
    going: bool = field(default=False)

    def settled(self, s: float) -> bool:
        """Whether the NPC, at arc length s, waits for the ego no more, for good: it went, or
        is past its stop point (an NPC never moves back along its path)."""
        return self.going or s > self.stop_i

    def wait_gap(self, s: float, v: float, s_ego: float, v_ego: float) -> float | None:
        """The NPC's distance to its stop point while it waits; None when it may go."""
        if self.settled(s) or self.s_i - s > DECIDE_WITHIN_M:
            return None
        to_ego = self.s_ego - s_ego
        if to_ego < -PASSED_M:  # the ego is through
            self.going = True
            return None
        t_npc = (self.s_i - s) / max(v, 1.0)
        t_ego = to_ego / max(v_ego, 0.1)
        if t_ego > t_npc + self.gap_s:
            self.going = v * v > 2.0 * COMMIT_DECEL_MPS2 * max(self.stop_i - s, 0.0)
            return None
        return self.stop_i - s
