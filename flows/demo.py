"""The main job, small, as one Prefect flow: `python -m flows.demo` (what `make demo` runs).

simulate both logical scenarios → ingest → train the FusionMonitor and evaluate it against the
TTC / TTC-2D / RSS / AEM baselines and the context-only control (RQ1 report) → one evolution
round of BlindSpotEvolver. With no Prefect API configured, Prefect starts a temporary local
server for the run; simulation fans out over local processes.
"""

from __future__ import annotations

import argparse
from typing import Any

from prefect import flow
from pydantic import BaseModel, Field

from evoeye.paths import DataRoot
from evoeye.scenarios import SCENARIOS
from flows.command_line import API_NOTE, say_what_we_wait_for
from flows.evaluate import EvaluateParams, evaluate_flow
from flows.evolve import EvolveParams, evolution_flow
from flows.ingest import IngestParams, ingest_flow
from flows.simulate import SimulateParams, simulate_batch_flow

EVOLVE_SCENARIO = "unprotected-intersection"


class DemoParams(BaseModel):
    """Sizes of the demo (defaults: a few minutes on 2 cores)."""

    root: str | None = None
    n: int = Field(40, ge=8, le=10_000)  # runs per logical scenario
    seed: int = Field(0, ge=0)
    workers: int = Field(2, ge=1, le=64)
    evolve_runs: int = Field(4, ge=1, le=100)  # runs in the one evolution round


@flow(name="evoeye-demo", log_prints=True)
def demo_flow(params: DemoParams) -> dict[str, Any]:
    """The whole pipeline once, end to end; returns where the results are."""
    data = DataRoot.resolve(params.root)
    root = str(data.path)  # the sub-flows' parameters: plain, as a user would give them
    for scenario in SCENARIOS:
        simulate_batch_flow(SimulateParams(scenario=scenario, n=params.n, seed=params.seed,
                                           root=root, workers=params.workers, batch="demo"))
    ingest_flow(IngestParams(root=root))
    rq1 = evaluate_flow(EvaluateParams(root=root, train_fusion=True, report_name="demo"))
    evolution = evolution_flow(EvolveParams(
        root=root, scenario=EVOLVE_SCENARIO, strategy="evoeye", n_round=params.evolve_runs,
        budget_s=20.0 * params.evolve_runs, max_rounds=1, epochs=2, assess=True,
    ))
    return {"runs": str(data.runs), "warehouse": str(data.warehouse),
            "monitors": str(data.monitors), "rq1": rq1, "evolution": evolution,
            "campaign_rounds": str(data.table_dir("campaign_rounds"))}


def main() -> None:
    ap = argparse.ArgumentParser(prog="python -m flows.demo", description=__doc__,
                                 epilog=API_NOTE)
    ap.add_argument("--root", default=None)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    try:
        params = DemoParams(root=args.root, n=args.n, workers=args.workers)
    except ValueError as exc:  # pydantic's ValidationError: one line per field, no traceback
        ap.error(" ".join(str(exc).split()))
    say_what_we_wait_for()
    result = demo_flow(params)
    print("\nevoeye demo finished. Results:")
    print(f"  MCAP logs (Foxglove / Lichtblick): {result['runs']}")
    print(f"  warehouse (Parquet + DuckDB):      {result['warehouse']}")
    print(f"  trained monitors and cards:        {result['monitors']}")
    print(f"  RQ1 report (Markdown + HTML):      {result['rq1']['report_dir']}")
    print(f"  evolution round state:             {result['campaign_rounds']}")


if __name__ == "__main__":
    main()
