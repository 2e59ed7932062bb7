"""Seed streams: each purpose draws from a numpy `SeedSequence` of its own, so none meets another.

* A **batch** at seed s (`evoeye.batch.plan_uniform`; a Test Set is such a batch at a seed of
  its own) draws its vectors from `default_rng(s)` and its run seeds from `SeedSequence(s)`: the
  streams every stored batch was drawn from, so batch run ids never change.
* A **campaign** of strategy a at seed s draws from `SeedSequence(s, spawn_key=(CAMPAIGN, …,
  tag(a), …))`: its strategy from the key `(CAMPAIGN, SEARCH, tag(a))` (`search_seed`), the run
  seed of its proposal k from `(CAMPAIGN, RUNS, tag(a), k, attempt)` (`campaign_run_seed`), so
  the campaigns of two strategies at one seed meet neither each other nor a batch. Campaigns of
  one strategy and seed that differ in their monitor's settings (`--update`, G_0, `--family`)
  share their draws until their feedback differs, by design: they are paired.

Why they cannot meet: a SeedSequence hashes its entropy as 32-bit words (zero-padded to its pool
of 4), followed by its spawn key. A batch's seed (< 2**64) is at most 2 words and no key: its
input is `[a, b, 0, 0]`. A campaign's run seeds add a 5-word key to that; its strategy's seed is
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


def tag(strategy: str) -> int:
    """A strategy's name as a 32-bit spawn-key word (the first 4 bytes of its SHA-256)."""
    return int.from_bytes(hashlib.sha256(strategy.encode()).digest()[:4], "little")


def search_seed(seed: int, strategy: str) -> int:
    """The seed a campaign of `strategy` at `seed` gives its strategy: 2**64 + a 64-bit draw (the
    third entropy word 1 keeps every stream of the strategy apart from every batch's)."""
    state = _stream(seed, CAMPAIGN, SEARCH, tag(strategy)).generate_state(1, "uint64")
    return 2**64 + int(state[0])


def campaign_run_seed(seed: int, strategy: str, k: int, attempt: int = 0) -> int:
    """The simulation seed of proposal k (0-based) of a campaign of `strategy` at `seed`;
    `attempt` > 0 when the seeds before it gave runs the data root already held."""
    return int(_stream(seed, CAMPAIGN, RUNS, tag(strategy), k, attempt).generate_state(1)[0])
