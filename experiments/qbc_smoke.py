"""A smoke-sized sample-efficiency study of Uniform against qbc (query-by-committee on the pool's
own windows), with sets too small for `evoeye results` to choose: a check that the curve runs
and what it costs, not a result.

    nice -n 10 python -m experiments.qbc_smoke --root DIR --seeds 0-2 --n-round 40 \\
        --checkpoints 80,160 --out qbc-smoke.json

Pool mode, no oracle, the per-round monitor retrained (`update="retrain"`, which neither curve
reads, so Uniform trains only its checkpoint monitors). The regime's data (pool, Test Set,
validation, a small boundary set and an oracle set no curve reads) is simulated first and
resumes; the study's page goes beside `--out` (qbc-smoke.md), its figures and CPU seconds into
`--out`.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from evoeye.paths import DataRoot
from evoeye.results.efficiency.config import QBC, REFERENCE, EfficiencyConfig
from evoeye.results.efficiency.data import prepare_regime
from evoeye.results.efficiency.part import run_efficiency
from evoeye.results.efficiency.report import efficiency_markdown
from experiments.ensemble_power import cpu_s, seeds_arg


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, required=True)
    parser.add_argument("--seeds", default="0-2")
    parser.add_argument("--regime", default="highway-cut-in")
    parser.add_argument("--pool", type=int, default=600)
    parser.add_argument("--test", type=int, default=300)
    parser.add_argument("--val", type=int, default=200)
    parser.add_argument("--boundary-pairs", type=int, default=30)
    parser.add_argument("--n-round", type=int, default=40)
    parser.add_argument("--checkpoints", default="80,160")
    parser.add_argument("--members", type=int, default=1)
    parser.add_argument("--out", type=Path, default=Path("qbc-smoke.json"))
    args = parser.parse_args()
    config = EfficiencyConfig(
        regimes=(args.regime,), mode="pool", update="retrain", strategies=(REFERENCE, QBC),
        seeds=seeds_arg(args.seeds), oracle=False, n_round=args.n_round,
        checkpoints=tuple(int(c) for c in args.checkpoints.split(",")),
        reference_checkpoints=(), pool_runs=args.pool, test_runs=args.test, val_runs=args.val,
        oracle_runs=20, boundary_pairs=args.boundary_pairs, members=args.members)
    root = DataRoot.resolve(args.root)
    out: dict = {"args": {k: str(v) for k, v in vars(args).items()}}
    t0, c0 = time.perf_counter(), cpu_s()
    prepare_regime(root, args.regime, config, say=print)
    out["data"] = {"cpu_s": cpu_s() - c0, "wall_s": time.perf_counter() - t0}
    t0, c0 = time.perf_counter(), cpu_s()
    results = run_efficiency(root, config, say=print)
    out["curves"] = {"cpu_s": cpu_s() - c0, "wall_s": time.perf_counter() - t0}
    regime = results["regimes"][args.regime]
    out["summary"] = regime["summaries"]["test/scratch"]
    out["found"] = regime["found"]
    args.out.with_suffix(".md").write_text(efficiency_markdown(results), encoding="utf-8")
    args.out.write_text(json.dumps(out, indent=1), encoding="utf-8")
    print(json.dumps({k: out[k] for k in ("data", "curves")}))


if __name__ == "__main__":
    main()
