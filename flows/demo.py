"""The demo as one Prefect flow run: `python -m flows.demo` (what `make demo` runs).

The steps of `evoeye.results.demo`, each a flow or task run: simulate fresh runs of every logical
scenario that ships a demo monitor (or of `--scenario`'s) and ingest them; measure the
FusionMonitor shipped with evoeye against the rule-based baselines on their test runs; the
FusionMonitor and TTC-2D as triggers of an emergency brake on those runs (the closed loop); one
evolution round per scenario from the shipped monitor; then the report and the plain-words
summary, printed at the end and published as an artifact. With no PREFECT_API_URL one temporary
API server serves the whole run.
"""

from __future__ import annotations

import argparse
from typing import Any

from prefect import flow, task
from prefect.cache_policies import NONE
from pydantic import BaseModel, Field

from evoeye.paths import DataRoot
from evoeye.results import demo as steps
from evoeye.store.feedback import read_rounds
from flows.api import one_api_server
from flows.command_line import API_NOTE, say_what_we_wait_for
from flows.evolve import EvolveParams, evolution_flow
from flows.ingest import IngestParams, ingest_flow
from flows.published import named, publish
from flows.simulate import SimulateParams, simulate_batch_flow


class DemoParams(BaseModel):
    """Sizes of the demo (defaults: a few minutes on 2 cores)."""

    root: str | None = None
    scenarios: list[str] | None = None  # default: every one that ships a demo monitor
    n: int | None = Field(None, ge=8, le=10_000)  # runs per scenario (default steps.runs_of)
    seed: int = Field(0, ge=0)
    workers: int = Field(2, ge=1, le=64)
    evolve_runs: int = Field(steps.EVOLVE_RUNS, ge=1, le=100)  # runs of each evolution round

    def run_name(self) -> str:
        return f"demo-{DataRoot.resolve(self.root).path.name}"


@task(cache_policy=NONE, task_run_name="evaluate-{scenario}")
def evaluate_shipped(root: DataRoot, scenario: str) -> dict:
    """The shipped monitor against the rule-based baselines on the scenario's test runs."""
    return steps.evaluate_shipped(root, scenario)


@task(cache_policy=NONE, task_run_name="in-the-loop-{scenario}")
def supervise_shipped(root: DataRoot, scenario: str, workers: int) -> dict:
    """The shipped monitor and TTC-2D as triggers of the production fallback on the test runs,
    every operating point chosen on the validation runs."""
    return steps.supervise_shipped(root, scenario, workers)


@flow(name="evoeye-demo", log_prints=True, flow_run_name=named(DemoParams.run_name))
def demo_flow(params: DemoParams) -> dict[str, Any]:
    """The demo end to end; its summary, and where the results are."""
    data = DataRoot.resolve(params.root)
    root = str(data.path)  # the sub-flows' parameters: plain, as a user would give them
    scenarios, skipped = steps.plan(params.scenarios)
    if skipped:
        print(steps.skipped_line(skipped))
    for scenario in scenarios:
        simulate_batch_flow(SimulateParams(scenario=scenario, seed=params.seed, root=root,
                                           n=params.n or steps.runs_of(scenario),
                                           workers=params.workers, batch=steps.BATCH))
    ingest_flow(IngestParams(root=root))
    result = steps.DemoResult(data, [evaluate_shipped(data, s) for s in scenarios])
    result.loop = {s: supervise_shipped(data, s, params.workers) for s in scenarios}
    for scenario in scenarios:
        cfg = steps.campaign_config(data, scenario, params.evolve_runs)
        out = evolution_flow(EvolveParams.of(cfg, root, max_rounds=1, assess=True))
        result.rounds[scenario] = read_rounds(data, out["campaign_id"])
    steps.write_summary(result)
    text = steps.summary_text(result)
    publish("evoeye-demo", f"```\n{text}\n```", str(result.report_dir))
    return {"summary": text, "paths": [(what, str(path)) for what, path in result.paths()]}


def main() -> None:
    ap = argparse.ArgumentParser(prog="python -m flows.demo", description=__doc__,
                                 epilog=API_NOTE)
    ap.add_argument("--root", default=None)
    ap.add_argument("--scenario", default=None,
                    help="NAME[,NAME]: only these logical scenarios (default: every one that "
                         "ships a demo monitor)")
    ap.add_argument("--n", type=int, default=None,
                    help="runs per logical scenario (default: the scenario's own)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--evolve-runs", type=int, default=steps.EVOLVE_RUNS)
    args = ap.parse_args()
    try:
        params = DemoParams(root=args.root, n=args.n, workers=args.workers,
                            evolve_runs=args.evolve_runs, scenarios=args.scenario and [
                                s.strip() for s in args.scenario.split(",") if s.strip()])
        steps.plan(params.scenarios)  # an unknown name: one line naming the known ones
    except ValueError as exc:  # pydantic's ValidationError: one line per field, no traceback
        ap.error(" ".join(str(exc).split()))
    say_what_we_wait_for()
    with one_api_server():
        result = demo_flow(params)
    print("\n" + result["summary"])
    print("\nWhere the results are:")
    for what, path in result["paths"]:
        print(f"  {what}: {path}")


if __name__ == "__main__":
    main()
