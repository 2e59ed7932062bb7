"""A batch's stream drawn on for its collisions: outcome first, only collisions logged, and a
killed draw resumed at its first missing chunk."""

from __future__ import annotations

from evoeye.batch import plan_uniform
from evoeye.paths import DataRoot
from evoeye.results.efficiency.stream import collisions, draw_on
from evoeye.sim.runner import run_episode

REGIME = "highway-cut-in:default"  # collisions are common: a short stream holds some
SEED, START, CHUNK = 77, 4, 4


def test_a_draw_stops_when_told_and_resumes_at_its_first_missing_chunk(tmp_path) -> None:
    data = DataRoot.resolve(tmp_path / "data")
    record = data.path / "draw.json"
    said: list[str] = []

    def draw(max_chunks: int, want: int = 10**9, held: int = 0):
        return draw_on(data, REGIME, SEED, START, CHUNK, "more", record, want, max_chunks,
                       held=held, say=said.append)

    first = draw(1)  # as if killed after one chunk
    assert len(first) == 1 and len(said) == 1 and f"runs {START}–{START + CHUNK - 1}" in said[0]
    said.clear()
    both = draw(2)
    assert both[0] == first[0] and len(both) == 2
    assert len(said) == 1 and f"runs {START + CHUNK}–" in said[0]  # only the missing chunk
    stream = plan_uniform("highway-cut-in", START + 2 * CHUNK, SEED, batch="more")[START:]
    hit = [s.scenario_id for s in stream if run_episode(s).outcome.collided]
    assert collisions(both) == hit and [c["ok"] for c in both] == [CHUNK, CHUNK]
    logged = sorted(p.name.removesuffix(".mcap") for p in data.path.rglob("*.mcap"))
    assert logged == sorted(hit)  # the safe runs were simulated for their outcome only
    said.clear()
    assert draw(1) == first and said == []  # less asked: a prefix of the record
    assert draw(2, want=3, held=3) == [] and said == []  # the batch held enough: no run
    again = len(collisions(both))  # wanted with 2 held: the shortest prefix holding them all
    shortest = next(k for k in range(3) if len(collisions(both[:k])) >= again)
    assert draw(2, want=again + 2, held=2) == both[:shortest]


def test_a_draw_says_how_many_collisions_it_holds_with_the_batchs(tmp_path) -> None:
    data = DataRoot.resolve(tmp_path / "data")
    said: list[str] = []
    draw_on(data, REGIME, SEED, START, CHUNK, "more", data.path / "draw.json", 50, 1, held=6,
            say=said.append)
    assert said == [f"{REGIME}: stream of seed {SEED}, runs {START}–{START + CHUNK - 1}: 6 of 50 "
                    "collisions so far, the batch's 6 included (outcome only, collisions "
                    "logged)"]
