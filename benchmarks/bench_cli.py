"""CLI start-up: `evoeye --help` and `evoeye <command> --help` against importing typer and rich.

Each command runs in a fresh interpreter (`python -m evoeye …`), `--repeat` times, interleaved
with the baseline `python -c "import typer, rich"` so that load on a shared machine hits both
alike; the figure is the ratio of medians of wall time (target ≤ 2×), and of CPU time, which
load disturbs less. Also shown: a minimal Typer app with two commands rendering its own
`--help` and a command's `--help` (typer ≥ 0.25 imports pydantic to build a command's
parameters), which is what typer itself costs.
"""

from __future__ import annotations

import argparse
import os
import resource
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


def _children_cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(argv: list[str]) -> tuple[float, float]:
    """(wall s, CPU s) of one run of the command."""
    t0, c0 = time.perf_counter(), _children_cpu_s()
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0, _children_cpu_s() - c0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=15)
    args = ap.parse_args()
    cases = {"import typer, rich": BASELINE, "tiny typer app --help": TINY_TYPER,
             "tiny typer app a --help": TINY_TYPER_CMD,
             **{k: [sys.executable, "-m", "evoeye", *v] for k, v in COMMANDS.items()}}
    times: dict[str, list[tuple[float, float]]] = {k: [] for k in cases}
    for _ in range(args.repeat):
        for name, argv in cases.items():
            times[name].append(timed(argv))
    base = [statistics.median(t[i] for t in times["import typer, rich"]) for i in (0, 1)]
    print(f"machine: {describe()}; load average {os.getloadavg()[0]:.1f}; "
          f"median of {args.repeat}\n")
    print("| command | wall s | × import typer, rich | CPU s | × import typer, rich |")
    print("|---|---:|---:|---:|---:|")
    for name, ts in times.items():
        wall, cpu = (statistics.median(t[i] for t in ts) for i in (0, 1))
        print(f"| `{name}` | {wall:.3f} | {wall / base[0]:.2f} | {cpu:.3f} | "
              f"{cpu / base[1]:.2f} |")


if __name__ == "__main__":
    main()
