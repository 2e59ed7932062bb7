"""Seed streams: each purpose draws from a numpy `SeedSequence` of its own, so none meets another.

* A **batch** at seed s (`evoeye.batch.plan_uniform`; a Test Set is such a batch at a seed of
  its own) draws its vectors from `default_rng(s)` and its run seeds from `SeedSequence(s)`: the
  streams every stored batch was drawn from, so batch run ids never change.
* A **campaign** with id c at seed s draws from `SeedSequence(s, spawn_key=(CAMPAIGN, …,
  *tag(c), …))`: its strategy from the key `(CAMPAIGN, SEARCH, *tag(c))` (`search_seed`), the
  run seed of its proposal k from `(CAMPAIGN, RUNS, *tag(c), k, attempt)` (`campaign_run_seed`),
  where tag(c) is two 32-bit words of the id's SHA-256. Two campaigns meet neither each other
  nor a batch — not even two of one strategy and seed that differ only in their monitor's
  settings (`--update`, G_0, the split): before, those drew the same runs, and the warehouse,
  which holds a run once, listed none of them under the second campaign.

Why they cannot meet: a SeedSequence hashes its entropy as 32-bit words (zero-padded to its pool
of 4), followed by its spawn key. A batch's seed (< 2**64) is at most 2 words and no key: its
input is `[a, b, 0, 0]`. A campaign's run seeds add a 6-word key to that; its strategy's seed is
2**64 + a 64-bit draw, whose third word is 1, so every `default_rng(seed)` and
`default_rng([seed, k])` of a strategy hashes `[a, b, 1, k]`. Before these streams, a
campaign's proposal k drew from `default_rng([s, k])`, and `[s, 0]` is `s` zero-padded:
proposal 0 of every uniform (and AV-Fuzzer) campaign at seed s was run 0 of the batch at seed s.
As a second guard the campaign redraws the run seed of any proposal whose run the data root
already holds (`evoeye.evolve.campaign.state.fresh_spec`).
"""

from __future__ import annotations

import hashlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from numpy.random import SeedSequence

CAMPAIGN = 1  # spawn-key purposes (0 is left free: a batch has no key)
SEARCH, RUNS = 0, 1  # a campaign's sub-streams

STREAMS_VERSION = 2  # hashed into campaign ids: campaigns before it drew `[seed, k]` streams


def _stream(seed: int, *key: int) -> SeedSequence:
    from numpy.random import SeedSequence  # here: the campaign config imports this module

    if seed < 0:
        raise ValueError(f"a seed must be non-negative, got {seed}")
    return SeedSequence(seed, spawn_key=key)


def tag(name: str) -> tuple[int, int]:
    """A campaign's id as two 32-bit spawn-key words (the first 8 bytes of its SHA-256)."""
    digest = hashlib.sha256(name.encode()).digest()
    return (int.from_bytes(digest[:4], "little"), int.from_bytes(digest[4:8], "little"))


def search_seed(seed: int, campaign: str) -> int:
    """The seed campaign `campaign` (its id) at `seed` gives its strategy: 2**64 + a 64-bit
    draw (the third entropy word 1 keeps every stream of the strategy apart from a batch's)."""
    state = _stream(seed, CAMPAIGN, SEARCH, *tag(campaign)).generate_state(1, "uint64")
    return 2**64 + int(state[0])


def campaign_run_seed(seed: int, campaign: str, k: int, attempt: int = 0) -> int:
    """The simulation seed of proposal k (0-based) of campaign `campaign` (its id) at `seed`;
    `attempt` > 0 when the seeds before it gave runs the data root already held."""
    return int(_stream(seed, CAMPAIGN, RUNS, *tag(campaign), k, attempt).generate_state(1)[0])
