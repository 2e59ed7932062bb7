"""The RQ2 experiment: G_0 vs every strategy at the same budget, R seeds, Test Set and Hard Set.

Each (scenario, strategy, seed) is one campaign (resumable, so a killed experiment re-run picks
up where it stopped); every round's G_r is assessed and stored with the round, so the per-round
curves come from the campaign_rounds table. The report (Markdown + self-contained HTML with SVG
charts) goes to `<root>/reports/<name>/`.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import replace
from datetime import UTC, datetime
from html import escape
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from evoeye.evaluation.plots import line_chart
from evoeye.evolve.assess import Assessor
from evoeye.evolve.campaign import Campaign, CampaignConfig, CampaignState, initial_monitor
from evoeye.paths import DataRoot
from evoeye.store import RunFilter
from evoeye.store.feedback import read_rounds

MAIN = ("uniform", "avfuzzer", "evoeye")
ABLATION = ("no-feedback", "no-density")
COLUMNS = ("f1@0.05", "f1@0.01", "auroc", "auprc")
ACQUISITION_HEAD = ("method", "runs", "collisions %", "within δ of an earlier record %")


def initial_budget_s(root: DataRoot, scenario: str, base: CampaignConfig) -> float:
    """Simulated seconds of D_init (the paper gives evolution the initial data's budget)."""
    return float(Campaign(root, replace(base, scenario=scenario)).initial["duration_s"].sum())


def plan_experiment(root: DataRoot | str | Path | None, scenarios: Sequence[str],
                    base: CampaignConfig, *, strategies: Sequence[str] = MAIN + ABLATION,
                    seeds: Sequence[int] = (0, 1, 2),
                    budget_s: float | None = None) -> list[CampaignConfig]:
    """Every campaign of the experiment, seed-major (a stopped experiment has whole repetitions).

    G_0 is resolved per scenario (`base.monitor` applies to `base.scenario` only); `budget_s`
    None gives each scenario the simulated time of its initial training data.
    """
    root = _root(root)
    plan = []
    for scenario in scenarios:
        g0 = (base.monitor if base.scenario == scenario and base.monitor
              else initial_monitor(root, scenario))
        budget = initial_budget_s(root, scenario, base) if budget_s is None else budget_s
        plan += [replace(base, scenario=scenario, strategy=strategy, seed=seed, monitor=g0,
                         budget_s=budget) for seed in seeds for strategy in strategies]
    return plan


def assessors(root: DataRoot | str | Path | None,
              plan: Sequence[CampaignConfig]) -> dict[str, Assessor]:
    """One Test/Hard Set assessor per scenario of the plan, against that scenario's G_0."""
    root = _root(root)
    return {c.scenario: Assessor(root, c.scenario, c.monitor, splits=c.splits,
                                 horizon_s=c.horizon_s) for c in plan}


def collect_results(root: DataRoot | str | Path | None, plan: Sequence[CampaignConfig]) -> dict:
    """{scenario: {"initial": G_0's metrics, "g0", strategy: [per-seed runs]}} from the stored
    rounds of the plan's campaigns (round 0 holds G_0's assessment)."""
    root = _root(root)
    out: dict = {}
    for cfg in plan:
        c = Campaign(root, cfg)
        rows = read_rounds(root, c.campaign_id)
        if not rows:
            continue  # not started yet
        rounds = [json.loads(r.metrics) if r.metrics else None for r in rows]
        res = out.setdefault(cfg.scenario, {"initial": rounds[0], "g0": cfg.monitor})
        state = c.start()
        res.setdefault(cfg.strategy, []).append({
            "campaign_id": c.campaign_id, "seed": cfg.seed, "rounds": rounds,
            "budget_s": cfg.budget_s, "simulated_s": rows[-1].simulated_s,
            "records": rows[-1].n_records, "acquisition": acquisition(c, state),
            "blind_spots": _blind_spots(c, state) if cfg.strategy == "evoeye" else None,
        })
    return out


def run_experiment(root: DataRoot | str | Path | None, scenarios: Sequence[str],
                   base: CampaignConfig, *, strategies: Sequence[str] = MAIN + ABLATION,
                   seeds: Sequence[int] = (0, 1, 2), budget_s: float | None = None,
                   controls: int = 3, progress: Callable[[str], None] = print) -> dict:
    """Run (or resume) every campaign of the plan, then `collect_results`, with `controls`
    re-seeded G_0 per scenario."""
    root = _root(root)
    plan = plan_experiment(root, scenarios, base, strategies=strategies, seeds=seeds,
                           budget_s=budget_s)
    assess = assessors(root, plan)
    for cfg in plan:
        c = Campaign(root, cfg, assess=assess[cfg.scenario])
        progress(f"{cfg.scenario} {cfg.strategy} seed {cfg.seed}: campaign {c.campaign_id}, "
                 f"budget {cfg.budget_s:.0f} s")
        c.run(on_round=lambda row, st, s=cfg.strategy: progress(
            f"  {s} round {row.round}: {_brief(row.metrics)}"))
    return add_controls(root, plan, collect_results(root, plan), controls, assess, progress)


def add_controls(root: DataRoot | str | Path | None, plan: Sequence[CampaignConfig],
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


def reseeded_controls(root: DataRoot | str | Path | None, cfg: CampaignConfig, k: int,
                      assess: Assessor) -> list[dict]:
    """The control without new data: G_0's recipe retrained on D_init with k other seeds.

    The Hard Set is defined by G_0's own misses, so any other model — even one trained on the
    same data — scores above G_0's 0 on it; a strategy has only improved on the Hard Set by what
    it adds over these. Versions already trained (same runs, seed, from scratch) are reused.
    """
    from evoeye.monitor import list_versions, read_card, train_monitor
    from evoeye.monitor.card import describe_selection

    root = _root(root)
    ids = [str(s) for s in Campaign(root, cfg).initial["scenario_id"]]
    selection = describe_selection(ids)
    have = {}
    for v in list_versions(root):
        card = read_card(root, v)
        if (card.get("logical_scenario") == cfg.scenario and not card.get("parent")
                and card.get("selection", {}).get("train") == selection):
            have[card.get("hyperparameters", {}).get("seed")] = v
    val = RunFilter(logical_scenario=cfg.scenario, split="val", splits=cfg.splits)
    out = []
    for seed in range(CONTROL_SEED, CONTROL_SEED + k):
        version = have.get(seed) or train_monitor(
            root, cfg.scenario, train_runs=ids, val_runs=val, seed=seed, splits=cfg.splits,
            horizon_s=cfg.horizon_s)
        out.append(assess(version))
    return out


def _root(root: DataRoot | str | Path | None) -> DataRoot:
    return root if isinstance(root, DataRoot) else DataRoot.resolve(root)


def _brief(metrics: str) -> str:
    if not metrics:
        return ""
    m = json.loads(metrics)
    return (f"test F1@0.05 {m['test']['f1@0.05']:.3f} AUPRC {m['test']['auprc'] or 0:.3f} | "
            f"hard F1@0.05 {m['hard']['f1@0.05']:.3f}")


def acquisition(c: Campaign, st: CampaignState) -> dict:
    """What a campaign acquired: runs, their collision share, and the share of runs within δ
    (Chebyshev) of an earlier record — local mutations, in effect (a uniform sample lands that
    close with probability ≈ n·(2δ)^dim)."""
    u = c.space.normalise(st.records.params)
    near = [np.abs(u[:i] - u[i]).max(axis=1).min() <= c.config.delta
            for i in range(st.n_init, st.records.n)]
    new = st.records.tail(st.n_init)
    return {"runs": int(new.n), "collision_share": float(np.mean(new.collided)) if new.n else 0.0,
            "near_share": float(np.mean(near)) if near else 0.0}


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


def _value(v: float | None) -> float:
    """A metric as a float; None (undefined, e.g. AUPRC with one class) becomes NaN."""
    return np.nan if v is None else float(v)


def _final(run: dict, split: str, col: str) -> float:
    return _value(run["rounds"][-1][split][col])


def _mean_std(values: list[float]) -> str:
    a = np.asarray(values, float)
    if not len(a):
        return "–"
    mean = f"{100 * np.nanmean(a):.1f}"
    # one seed has no spread to report: "± 0.0" would read as zero variance
    return f"{mean} ± {100 * np.nanstd(a):.1f}" if np.isfinite(a).sum() > 1 else mean


def table_rows(res: dict, strategies: Sequence[str]) -> list[list[str]]:
    """Rows: method, then mean ± std (in %) of each column on the Test Set and the Hard Set."""
    rows = [["initial (G_0)"] + [_mean_std([_value(res["initial"][s][c])])
                                 for s in ("test", "hard") for c in COLUMNS]]
    if res.get("reseeded"):
        rows.append([f"G_0 re-seeded ×{len(res['reseeded'])} (no new data)"]
                    + [_mean_std([_value(m[s][c]) for m in res["reseeded"]])
                       for s in ("test", "hard") for c in COLUMNS])
    for strategy in strategies:
        runs = res.get(strategy, [])
        rows.append([strategy] + [_mean_std([_final(r, s, c) for r in runs])
                                  for s in ("test", "hard") for c in COLUMNS])
    return rows


def acquisition_rows(res: dict) -> list[list[str]]:
    """Per strategy: acquired runs, collision share and near share (mean ± std over seeds)."""
    rows = []
    for strategy in MAIN + ABLATION:
        acq = [r["acquisition"] for r in res.get(strategy, []) if r.get("acquisition")]
        if acq:
            runs = np.array([a["runs"] for a in acq], float)
            runs_s = f"{runs.mean():.0f} ± {runs.std():.0f}" if len(runs) > 1 else f"{runs[0]:.0f}"
            rows.append([strategy, runs_s,
                         _mean_std([a["collision_share"] for a in acq]),
                         _mean_std([a["near_share"] for a in acq])])
    return rows


def markdown(results: dict) -> str:
    head = ["method"] + [f"{s} {c}" for s in ("Test", "Hard") for c in COLUMNS]
    out = ["# evoeye RQ2: self-evolution under the same budget", ""]
    for scenario, res in results.items():
        for title, strategies in (("RQ2", MAIN), ("Evolution ablation", ("evoeye",) + ABLATION)):
            out += [f"## {scenario} — {title} (mean ± std over seeds, %)", "",
                    "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
            out += ["| " + " | ".join(r) + " |" for r in table_rows(res, strategies)]
            out.append("")
        out += [f"## {scenario} — what each strategy acquired (mean ± std over seeds)", "",
                "| " + " | ".join(ACQUISITION_HEAD) + " |", "|---|---|---|---|"]
        out += ["| " + " | ".join(r) + " |" for r in acquisition_rows(res)]
        out.append("")
    return "\n".join(out)


def _curves(res: dict, split: str, col: str) -> str:
    series = []
    ran = {s: res[s] for s in MAIN + ABLATION if res.get(s)}
    n_max = max((len(r["rounds"]) for runs in ran.values() for r in runs), default=1)
    for strategy, runs in ran.items():
        n = min(len(r["rounds"]) for r in runs)
        ys = [float(np.nanmean([_value(r["rounds"][i][split][col]) for r in runs]))
              for i in range(n)]
        series.append((strategy, [i / max(n_max - 1, 1) for i in range(n)], ys))
    return line_chart(series, title=f"{split} {col} per round", xlabel="round (0 … last)",
                      ylabel=col)


def _scatter(b: dict) -> str:
    pts = []
    hi = max(b["feedback"]) or 1.0
    for x, y, f, new in zip(b["u0"], b["u1"], b["feedback"], b["acquired"], strict=True):
        red = int(255 * f / hi)
        pts.append(f'<circle cx="{40 + 300 * x:.1f}" cy="{330 - 300 * y:.1f}" r="{4 if new else 3}"'
                   f' fill="rgb({red},60,{255 - red})" stroke="{"#000" if new else "none"}"/>')
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="360" height="370">'
            f'<rect x="40" y="30" width="300" height="300" fill="none" stroke="#999"/>'
            f'{"".join(pts)}<text x="120" y="360">{escape(b["names"][0])}</text>'
            f'<text x="5" y="20">{escape(b["names"][1])} (red = high feedback, ringed = '
            f'acquired)</text></svg>')


def _html_table(head: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    cells = "".join("<tr>" + "".join(f"<td>{escape(c)}</td>" for c in r) + "</tr>" for r in rows)
    return ("<table border=1 cellpadding=3><tr>" + "".join(f"<th>{escape(h)}</th>" for h in head)
            + f"</tr>{cells}</table>")


def html(results: dict) -> str:
    body = []
    for scenario, res in results.items():
        body.append(f"<h2>{escape(scenario)}</h2>")
        for title, strategies in (("RQ2", MAIN), ("Evolution ablation", ("evoeye",) + ABLATION)):
            head = ["method"] + [f"{s} {c}" for s in ("Test", "Hard") for c in COLUMNS]
            body.append(f"<h3>{title}</h3>" + _html_table(head, table_rows(res, strategies)))
        body.append("<h3>What each strategy acquired</h3>" + _html_table(
            ACQUISITION_HEAD, acquisition_rows(res)))
        for split in ("test", "hard"):
            for col in ("f1@0.05", "auprc"):
                body.append(_curves(res, split, col))
        spots = [r["blind_spots"] for r in res.get("evoeye", []) if r.get("blind_spots")]
        if spots:
            body.append("<h3>Blind-spot map (EvoEye, first seed)</h3>" + _scatter(spots[0]))
    return ("<!doctype html><meta charset=utf-8><title>evoeye RQ2</title>"
            "<body style='font-family:sans-serif'>" + "".join(body) + "</body>")


def write_experiment_report(root: DataRoot | str | Path | None, results: dict,
                            name: str | None = None) -> Path:
    """rq2.md, rq2.html and rq2.json under `<root>/reports/<name>/`; the folder."""
    folder = _root(root).reports / (name or f"rq2-{datetime.now(UTC):%Y%m%dT%H%M%SZ}")
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "rq2.md").write_text(markdown(results), encoding="utf-8")
    (folder / "rq2.html").write_text(html(results), encoding="utf-8")
    (folder / "rq2.json").write_text(json.dumps(results, indent=1, default=float),
                                     encoding="utf-8")
    return folder
