"""CLI start-up: `evoeye --help` and `evoeye <command> --help` against importing typer and rich.

Each command runs in a fresh interpreter (`python -m evoeye …`), `--repeat` times, interleaved
with the baseline `python -c "import typer, rich"` so that load on a shared machine hits both
alike; the figure is the ratio of medians of wall time (target ≤ 2×). Also shown: a minimal
Typer app with two commands rendering its own `--help` and a command's `--help` (typer ≥ 0.25
imports pydantic to build a command's parameters), which is what typer itself costs.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

from benchmarks.machine import describe

BASELINE = [sys.executable, "-c", "import typer, rich"]
TINY = ("import typer; app = typer.Typer(); app.command('a')(lambda x: 1); "
        "app.command('b')(lambda y: 2); app()")
TINY_TYPER = [sys.executable, "-c", TINY, "--help"]
TINY_TYPER_CMD = [sys.executable, "-c", TINY, "a", "--help"]
COMMANDS = {
    "evoeye --help": ["--help"],
    "evoeye simulate --help": ["simulate", "--help"],
    "evoeye sql --help": ["sql", "--help"],
    "evoeye evolve --help": ["evolve", "--help"],
}


def wall_s(argv: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=15)
    args = ap.parse_args()
    cases = {"import typer, rich": BASELINE, "tiny typer app --help": TINY_TYPER,
             "tiny typer app a --help": TINY_TYPER_CMD,
             **{k: [sys.executable, "-m", "evoeye", *v] for k, v in COMMANDS.items()}}
    times: dict[str, list[float]] = {k: [] for k in cases}
    for _ in range(args.repeat):
        for name, argv in cases.items():
            times[name].append(wall_s(argv))
    base = statistics.median(times["import typer, rich"])
    print(f"machine: {describe()}; load average {os.getloadavg()[0]:.1f}; "
          f"median of {args.repeat}\n")
    print("| command | median s | × import typer, rich |")
    print("|---|---|---|")
    for name, ts in times.items():
        med = statistics.median(ts)
        print(f"| `{name}` | {med:.3f} | {med / base:.2f} |")


if __name__ == "__main__":
    main()
