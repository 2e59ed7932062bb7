"""Write the golden Autoware bag (tests/data/autoware/golden/): the first second of a simulated
highway-cut-in run, every topic on the 20 Hz clock, with its ground truth and collision topic.

    .venv/bin/python tests/data/autoware/make_golden.py   # rewrites golden/ beside this file

tests/sources/test_autoware_bags.py writes it again into a temporary folder and compares the
bytes, so a change of the exporter's conventions shows as a changed golden bag in review.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DURATION_S = 1.0


def golden_log(folder: Path) -> Path:
    """The first second of a simulated highway-cut-in run, as a run log in `folder`."""
    from evoeye.log import write_episode
    from evoeye.scenarios import get_scenario
    from evoeye.sim.runner import SimConfig, run_episode, run_spec

    space = get_scenario("highway-cut-in")
    spec = run_spec(space.name, space.sample(np.random.default_rng(0)), 0, batch="golden")
    episode = run_episode(spec, SimConfig(duration_s=DURATION_S))
    return write_episode(episode, Path(folder) / "run.mcap")


def golden_bag(out_dir: Path) -> Path:
    """The golden bag folder `<out_dir>/golden`."""
    from evoeye.sources.autoware.config import Mapping
    from evoeye.sources.autoware.export import RATES, bag_messages, write_bag

    with tempfile.TemporaryDirectory() as tmp:
        _, messages = bag_messages(golden_log(Path(tmp)), Mapping(), RATES["lossless"],
                                   collision=True)
    return write_bag(out_dir / "golden", messages)


if __name__ == "__main__":
    bag = golden_bag(HERE)
    print(bag, sum(p.stat().st_size for p in bag.rglob("*")), "bytes")
