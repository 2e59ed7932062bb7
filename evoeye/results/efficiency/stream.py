"""A uniform batch's stream drawn on past the batch, for its collisions: outcome first, resumable.

A set that needs failures where they are rare (a validation set enriched with collisions, a Test
Set with ≥ 50 of them) draws the stream of its uniform batch on: `plan_uniform` with the batch's
seed, a longer plan beginning with the shorter one, so the runs past the batch are the same
whatever was simulated before. The further runs are simulated in chunks of `chunk` runs for
their outcome, and only the colliding ones are logged (`run_batch(collisions_only=True)`): at
≈ 0.1 % the safe ones would be ≈ 1.3 MB of log each that no set reads. Each chunk's outcome
(runs that simulated, and the colliding ones in stream order) is kept in a record file as soon
as it is drawn: a killed draw resumes at its first missing chunk, and a draw that asks for less
than was drawn before uses the first chunks of the record without simulating anything.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

from evoeye.atomic import atomic_file
from evoeye.batch import DEFAULT_LOCKSTEP, plan_uniform, run_batch
from evoeye.paths import DataRoot
from evoeye.results.efficiency.config import parse_regime
from evoeye.sim.episode import STATUS_OK

Chunk = dict  # {"ok": runs that simulated, "collided": [their ids, in stream order]}
Say = Callable[[str], None]


def collisions(chunks: list[Chunk]) -> list[str]:
    """The colliding runs of `chunks`, in stream order."""
    return [i for c in chunks for i in c["collided"]]


def _recorded(record: Path, key: dict) -> list[Chunk]:
    found = json.loads(record.read_bytes()) if record.is_file() else {}
    return list(found["chunks"]) if {k: found.get(k) for k in key} == key else []


def draw_on(data: DataRoot, regime: str, seed: int, start: int, chunk: int, batch: str,
            record: Path, want: int, max_chunks: int, *, held: int = 0, workers: int = 1,
            say: Say | None = None) -> list[Chunk]:
    """The shortest run of chunks of the stream of `seed` past its first `start` runs (in batch
    `batch`) after which the set holds `want` collisions, `held` of them (the batch's) before
    the stream, or `max_chunks` chunks if none does (module doc); drawn where `record` does not
    hold them yet."""
    say = say or (lambda msg: None)
    scenario, profile = parse_regime(regime)
    key = {"regime": regime, "seed": seed, "start": start, "chunk": chunk}
    chunks, k = _recorded(record, key), 0
    while not (held + len(collisions(chunks[:k])) >= want or k == max_chunks):
        if k == len(chunks):
            first = start + k * chunk
            specs = plan_uniform(scenario, first + chunk, seed, batch=batch,
                                 ads=profile)[first:]
            say(f"{regime}: stream of seed {seed}, runs {first}–{first + chunk - 1}: "
                f"{held + len(collisions(chunks))} of {want} collisions so far, the batch's "
                f"{held} included (outcome only, collisions logged)")
            results = {r.scenario_id: r for r in run_batch(
                specs, data, workers=workers, collisions_only=True, lockstep=DEFAULT_LOCKSTEP,
            ).results}
            ok = [s.scenario_id for s in specs if results[s.scenario_id].status == STATUS_OK]
            chunks.append({"ok": len(ok), "collided": [i for i in ok if results[i].collided]})
            with atomic_file(record) as f:
                f.write(json.dumps({**key, "chunks": chunks}, indent=1).encode())
        k += 1
    return chunks[:k]
