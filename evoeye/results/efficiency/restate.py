"""The study's Markdown again from a stored results JSON, with the summaries of today's code:
its curves keep every figure per seed and budget, so a new summary (what the seeds could
detect, the failures found) needs no run again.

    python -m evoeye.results.efficiency.restate docs/results/efficiency-screen-rare.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from evoeye.results.efficiency.config import EfficiencyConfig
from evoeye.results.efficiency.part import regime_results
from evoeye.results.efficiency.report import efficiency_markdown


def restate(efficiency: dict) -> str:
    """efficiency.md of a results JSON's `efficiency` part, summarised again."""
    config = EfficiencyConfig.from_dict(efficiency["config"])
    regimes = {name: regime_results(r, config) for name, r in efficiency["regimes"].items()}
    return efficiency_markdown({"config": efficiency["config"], "regimes": regimes})


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m evoeye.results.efficiency.restate RESULTS.json", file=sys.stderr)
        return 2
    stored = json.loads(Path(args[0]).read_text())
    if "efficiency" not in stored:
        print(f"{args[0]}: no efficiency part in this results JSON", file=sys.stderr)
        return 2
    print(restate(stored["efficiency"]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
