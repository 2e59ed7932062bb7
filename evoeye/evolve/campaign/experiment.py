"""The RQ2 experiment: G_0 vs every strategy at the same budget, R seeds, Test Set and Hard Set.

A method is a strategy evolving the FusionMonitor, or `<family>-evo`: the `evoeye` strategy
evolving another evolvable monitor family, e.g. `aem-evo` for the AEM baseline (paper RQ3),
judged on the same Test Set and the FusionMonitor G_0's Hard Set.
Each (scenario, method, seed) is one campaign (resumable, so a killed experiment re-run picks
up where it stopped); the campaigns are independent and run side by side, over local processes
or a Dask cluster (`workers.py`). Every round's G_r is assessed and stored with the round, so
the per-round curves come from the campaign_rounds table. The report (Markdown +
self-contained HTML with SVG charts, `report.py`) goes to `<root>/reports/<name>/`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np
from scipy.stats import spearmanr

from evoeye.evaluation.report import UNREACHABLE
from evoeye.evolve.campaign.assess import Assessor
from evoeye.evolve.campaign.committee import from_scratch
from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.loop import Campaign
from evoeye.evolve.campaign.state import CampaignState, read_initial
from evoeye.evolve.campaign.workers import CampaignJob, assessor, run_campaigns
from evoeye.evolve.search.fitness import CRITICALITY_SCALE_M
from evoeye.evolve.search.registry import STRATEGIES
from evoeye.monitor.families import DEFAULT_FAMILY, evolvable_families, initial_monitor
from evoeye.paths import DataRoot
from evoeye.store.connections import shared_connections
from evoeye.store.feedback import RoundMetrics, RoundRow, read_rounds
from evoeye.store.ingest import refresh_catalog
from evoeye.store.windows import cached_parts

MAIN = ("uniform", "avfuzzer", "evoeye")
ABLATION = ("no-feedback", "no-density", "aem-evo")
EVOLVE_OTHER = "evoeye"  # the strategy a `<family>-evo` method runs on another family


def methods() -> dict[str, tuple[str, str]]:
    """Method → (strategy, monitor family): every registered strategy on the FusionMonitor,
    and `<family>-evo` for every other evolvable family."""
    return {**{s: (s, DEFAULT_FAMILY) for s in STRATEGIES},
            **{f"{f}-evo": (EVOLVE_OTHER, f) for f in evolvable_families() if f != DEFAULT_FAMILY}}


def method_of(cfg: CampaignConfig) -> str:
    return cfg.strategy if cfg.family == DEFAULT_FAMILY else f"{cfg.family}-evo"


def initial_budget_s(root: DataRoot, scenario: str, base: CampaignConfig) -> float:
    """Simulated seconds of D_init (the paper gives evolution the initial data's budget)."""
    return float(Campaign(root, replace(base, scenario=scenario)).initial["duration_s"].sum())


def plan_experiment(root: DataRoot, scenarios: Sequence[str],
                    base: CampaignConfig, *, strategies: Sequence[str] = MAIN + ABLATION,
                    seeds: Sequence[int] = (0, 1, 2),
                    budget_s: float | None = None) -> list[CampaignConfig]:
    """Every campaign of the experiment, seed-major (a stopped experiment has whole repetitions).

    G_0 is resolved per scenario (`base.monitor` applies to `base.scenario` only); `budget_s`
    None gives each scenario the simulated time of its initial training data. An `aem-evo`
    campaign starts from the AEM trained on D_init and is judged on G_0's Hard Set.
    """
    known = methods()
    unknown = sorted(set(strategies) - set(known))
    if unknown:
        raise ValueError(f"unknown method(s) {unknown}; known: {sorted(known)}")
    plan = []
    for scenario in scenarios:
        g0 = (base.monitor if base.scenario == scenario and base.monitor
              else initial_monitor(root, scenario))
        budget = initial_budget_s(root, scenario, base) if budget_s is None else budget_s
        for seed in seeds:
            for method in strategies:
                strategy, family = known[method]
                own = family == DEFAULT_FAMILY
                plan.append(replace(base, scenario=scenario, strategy=strategy, seed=seed,
                                    budget_s=budget, family=family, monitor=g0 if own else None,
                                    reference=None if own else g0))
    return plan


def assessors(root: DataRoot,
              plan: Sequence[CampaignConfig]) -> dict[str, Assessor]:
    """One Test/Hard Set assessor per scenario of the plan, against that scenario's G_0 (this
    process's, built once: `workers.assessor`)."""
    first = {c.scenario: c for c in reversed(plan)}  # one each: an Assessor loads the Test Set
    return {scenario: assessor(Campaign(root, c)) for scenario, c in first.items()}


def collect_results(root: DataRoot, plan: Sequence[CampaignConfig]) -> dict:
    """{scenario: {"initial": G_0's metrics, "g0", strategy: [per-seed runs]}} from the stored
    rounds of the plan's campaigns (round 0 holds G_0's assessment)."""
    out: dict = {}
    with cached_parts(), shared_connections():  # one database and one decode per part, for all
        for c in campaigns_of(root, plan):
            _collect(c, out)
    return out


def campaigns_of(root: DataRoot, plan: Sequence[CampaignConfig]) -> list[Campaign]:
    """A campaign per config of the plan, D_init read once per scenario and split (it is the
    same for every campaign that shares them)."""
    read: dict[tuple, dict[str, np.ndarray]] = {}
    for cfg in plan:
        key = (cfg.scenario, cfg.splits)
        if key not in read:
            read[key] = read_initial(root, cfg.scenario, cfg.splits)
    return [Campaign(root, cfg, initial=read[(cfg.scenario, cfg.splits)]) for cfg in plan]


def _collect(c: Campaign, out: dict) -> None:
    """Add one campaign's stored rounds, acquisition and blind spots to `out` (nothing for a
    campaign not started yet)."""
    cfg = c.config
    rows = read_rounds(c.root, c.campaign_id)
    if not rows:
        return
    rounds = [r.metrics.as_dict() if r.metrics else None for r in rows]
    res = out.setdefault(cfg.scenario, {"g0": c.reference})
    res.setdefault("initial" if cfg.family == DEFAULT_FAMILY else f"{cfg.family}-initial",
                   rounds[0])
    state = c.start()
    method = method_of(cfg)
    res.setdefault(method, []).append({
        "campaign_id": c.campaign_id, "seed": cfg.seed, "rounds": rounds,
        "budget_s": cfg.budget_s, "simulated_s": rows[-1].simulated_s,
        "records": rows[-1].n_records,
        "acquisition": {**acquisition(c, state),
                        "feedback": chosen_feedback(c.stored_feedback, rows)},
        "blind_spots": _blind_spots(c, state) if method == "evoeye" else None,
    })


def campaign_jobs(root: DataRoot, plan: Sequence[CampaignConfig]) -> list[CampaignJob]:
    """The plan's campaigns as jobs for `run_campaigns`, each assessed every round."""
    return [CampaignJob(str(root.path), cfg, f"{cfg.scenario} {method_of(cfg)} seed {cfg.seed}")
            for cfg in plan]


def run_experiment(root: DataRoot, scenarios: Sequence[str],
                   base: CampaignConfig, *, strategies: Sequence[str] = MAIN + ABLATION,
                   seeds: Sequence[int] = (0, 1, 2), budget_s: float | None = None,
                   controls: int = 3, progress: Callable[[str], None] = print,
                   workers: int | None = None, dask_address: str | None = None,
                   plan: Sequence[CampaignConfig] | None = None) -> dict:
    """Run (or resume) every campaign of the plan — over `workers` local processes (default:
    one per CPU; 1: one after another here) or the Dask cluster at `dask_address` — then
    `collect_results`, with `controls` re-seeded G_0 per scenario. `plan`: the
    `plan_experiment` of the same arguments, if the caller has it already."""
    if plan is None:
        plan = plan_experiment(root, scenarios, base, strategies=strategies, seeds=seeds,
                               budget_s=budget_s)
    jobs = campaign_jobs(root, plan)
    for job in jobs:
        progress(f"{job.label}: budget {job.config.budget_s:.0f} s")
    run_campaigns(jobs, workers=workers, dask_address=dask_address, brief=brief,
                  progress=progress)
    refresh_catalog(root)
    return add_controls(root, plan, collect_results(root, plan), controls,
                        assessors(root, plan), progress)


def add_controls(root: DataRoot, plan: Sequence[CampaignConfig],
                 results: dict, k: int, assess: dict[str, Assessor] | None = None,
                 progress: Callable[[str], None] | None = None) -> dict:
    """`results` with k re-seeded G_0 controls per scenario under "reseeded"."""
    if not k:
        return results
    assess = assess or assessors(root, plan)
    for scenario, cfg in {c.scenario: c for c in plan}.items():
        if scenario in results:
            if progress:
                progress(f"{scenario}: {k} re-seeded G_0 controls")
            results[scenario]["reseeded"] = reseeded_controls(root, cfg, k, assess[scenario])
    return results


CONTROL_SEED = 1000  # training seeds of the re-seeded G_0 controls: 1000, 1001, …


def reseeded_controls(root: DataRoot, cfg: CampaignConfig, k: int,
                      assess: Assessor) -> list[dict]:
    """The control without new data: G_0's recipe retrained on D_init with k other seeds.

    The Hard Set is defined by G_0's own misses, so any other model — even one trained on the
    same data — scores above G_0's 0 on it; a strategy has only improved on the Hard Set by what
    it adds over these. Versions already trained (same runs, seed, from scratch) are reused.
    """
    campaign = Campaign(root, cfg)
    ids = [str(s) for s in campaign.initial["scenario_id"]]
    out = []
    for seed in range(CONTROL_SEED, CONTROL_SEED + k):
        version = from_scratch(root, cfg.scenario, ids, campaign.val_runs, seed, cfg.splits,
                               cfg.horizon_s, recipe=cfg.recipe)
        out.append(assess(version).as_dict())
    return out



def brief(metrics: RoundMetrics | None) -> str:
    """A round's metrics in one line ('' if it was not assessed)."""
    if metrics is None:
        return ""
    t, h = metrics.test, metrics.hard
    return (f"test F1@0.05 {_f1(t)} AUPRC {t['auprc'] or 0:.3f} | "
            f"hard F1@0.05 {_f1(h)}")


def _f1(split: dict) -> str:
    """F1 at the first target FPR, or n/r where that target was unreachable (its F1 is None)."""
    return UNREACHABLE if split["f1@0.05"] is None else f"{split['f1@0.05']:.3f}"


NEAR_MISS_M = 1.0  # a collision-free run whose footprints came this close is a near miss


def acquisition(c: Campaign, st: CampaignState) -> dict:
    """What a campaign acquired: runs, their collision share, the share of near misses
    (collision-free, min footprint gap < 1 m; from the AV-Fuzzer criticality of each record),
    and the share of runs within δ (Chebyshev) of an earlier record — local mutations, in
    effect (a uniform sample lands that close with probability ≈ n·(2δ)^dim)."""
    u = c.space.normalise(st.records.params)
    near = [np.abs(u[:i] - u[i]).max(axis=1).min() <= c.config.delta
            for i in range(st.n_init, st.records.n)]
    new = st.records.tail(st.n_init)
    if not new.n:
        return {"runs": 0, "collision_share": 0.0, "near_miss_share": 0.0, "near_share": 0.0}
    gap_m = (np.full(new.n, np.nan) if new.fitness is None
             else np.asarray(new.fitness, float) * CRITICALITY_SCALE_M)
    miss = ~np.asarray(new.collided, bool) & (gap_m < NEAR_MISS_M)
    return {"runs": int(new.n), "collision_share": float(np.mean(new.collided)),
            "near_miss_share": float(np.mean(miss)), "near_share": float(np.mean(near))}


def chosen_feedback(stored_feedback: Callable[[str], dict[str, float]],
                    rounds: Sequence[RoundRow]) -> float | None:
    """The mean feedback of the runs a campaign acquired, each under G_{r-1}, the monitor whose
    errors chose it (rounds[r - 1]'s version for round r's runs; `stored_feedback`: version →
    {run: f} in the campaign's mode, `Campaign.stored_feedback`): how wrong the monitor was
    where the strategy looked. Uniform sampling gives the error of a random run; a strategy
    that finds the monitor's blind spots scores above it. None if no round stored any."""
    values: list[float] = []
    for chooser, row in zip(rounds, rounds[1:], strict=False):
        stored = stored_feedback(chooser.monitor_version)
        values += [stored[s] for s in row.scenario_ids if s in stored]
    return float(np.mean(values)) if values else None


def map_axes(u: np.ndarray, feedback: np.ndarray) -> tuple[int, int]:
    """The two parameters the feedback varies with most (largest |Spearman ρ|; ties: first)."""
    ok = np.isfinite(feedback)
    rho = np.zeros(u.shape[1])
    if ok.sum() > 2 and np.ptp(feedback[ok]) > 0:
        for j in range(u.shape[1]):
            if np.ptp(u[ok, j]) > 0:
                rho[j] = abs(spearmanr(u[ok, j], feedback[ok]).statistic)
    first, second = np.argsort(-rho, kind="stable")[:2]
    return int(first), int(second)


def _blind_spots(c: Campaign, st: CampaignState) -> dict:
    """The blind-spot map: every record's feedback under the final monitor over the two
    (normalised) parameters it depends on most."""
    u = c.space.normalise(st.records.params)
    i, j = map_axes(u, st.records.feedback)
    return {"names": [c.space.names[i], c.space.names[j]], "u0": u[:, i].tolist(),
            "u1": u[:, j].tolist(), "feedback": np.nan_to_num(st.records.feedback).tolist(),
            "acquired": [k >= st.n_init for k in range(st.records.n)]}


