"""Run every benchmark in turn: `python -m benchmarks`."""

import runpy
import sys

for module in ("benchmarks.bench_sim", "benchmarks.bench_warehouse", "benchmarks.bench_monitor",
               "benchmarks.bench_cli", "benchmarks.bench_campaign", "benchmarks.bench_experiment",
               "benchmarks.bench_watch", "benchmarks.bench_views",
               "benchmarks.bench_strategies"):
    print(f"\n## {module}\n", flush=True)
    sys.argv = [module]
    runpy.run_module(module, run_name="__main__")
