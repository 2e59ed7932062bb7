"""Write the golden Autoware bag (tests/data/autoware/golden/): the first second of a simulated
highway-cut-in run, every topic on the 20 Hz clock, with its ground truth and collision topic.

    .venv/bin/python tests/data/autoware/make_golden.py          # rewrites golden/ from the log
    .venv/bin/python tests/data/autoware/make_golden.py --log    # simulates the log first

tests/sources/test_autoware_bags.py writes it again into a temporary folder and compares the
bytes, so a change of the exporter's conventions shows as a changed golden bag in review.

The run log both golden files are exported from is stored beside (golden-run.mcap.xz), not
simulated by the tests: the simulation's last bits depend on the CPU (on an AVX2 machine one
prediction point of this second came out one ulp from the AVX-512 machine's that wrote the
first goldens, most likely where numpy's float64 functions take SIMD paths on one CPU and not
the other; not traced further), and the goldens test the exporters, not the simulator.
Re-simulate it (`--log`) when the log's format changes.
"""

from __future__ import annotations

import lzma
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DURATION_S = 1.0
LOG = HERE / "golden-run.mcap.xz"


def golden_log(folder: Path) -> Path:
    """The stored golden run log (module doc), as `<folder>/run.mcap`."""
    path = Path(folder) / "run.mcap"
    path.write_bytes(lzma.decompress(LOG.read_bytes()))
    return path


def simulated_log(folder: Path) -> Path:
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
    if "--log" in sys.argv[1:]:
        with tempfile.TemporaryDirectory() as tmp:
            LOG.write_bytes(lzma.compress(simulated_log(Path(tmp)).read_bytes(), preset=9))
        print(LOG, LOG.stat().st_size, "bytes")
    bag = golden_bag(HERE)
    print(bag, sum(p.stat().st_size for p in bag.rglob("*")), "bytes")
