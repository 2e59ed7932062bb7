"""The study's Markdown (efficiency.md, and its claims in findings.md) and its charts.

Every cell renders like the other results tables (`evoeye.results.markdown`): a strategy's
cell is its mean over seeds and the Student-t 95 % CI in points (AUPRC × 100); a comparison
is the mean paired difference with Uniform, its BCa bootstrap 95 % CI and the Wilcoxon p.
"""

from __future__ import annotations

from html import escape

from evoeye.evaluation.plots import band_chart
from evoeye.results.efficiency.config import (
    ORACLE,
    ORACLE_SEEDS,
    ORACLE_UNIFORM,
    QBC,
    REFERENCE,
    parse_regime,
)
from evoeye.results.efficiency.curves import MARGIN_BINS_M
from evoeye.results.efficiency.found import PER
from evoeye.results.markdown import diff_cell, md_table, mean_cell, pct

SET_WORDS = {"test": "the Test Set", "boundary": "the boundary set"}
KIND_WORDS = {"scratch": "the monitor trained from scratch on the runs acquired so far",
              "update": "the per-round monitor, fine-tuned every round by the paper's replay "
                        "rule (the one feedback-reading strategies steer by)"}
INTRO = (
    "Learning curves: from {initial} initial uniform runs (the same for every strategy at a "
    "seed), each strategy acquires runs in rounds of {n_round} ({mode}); at {budgets} runs a "
    "monitor is trained from scratch on everything acquired, with the training seed every "
    "strategy gets at that seed and budget, and judged on sets no strategy shaped. Seeds "
    "{seeds}, paired across strategies. *Area*: the curve's mean height on a log-budget axis. "
    "*Uniform's budget ×*: the budget Uniform's mean curve needs to reach the strategy's final "
    "mean, over the strategy's budget (≥ 1.5: Uniform needs 1.5× the runs; censored \">\" "
    "past Uniform's last point), with its bootstrap 95 % CI.")
ORACLE_WORDS = (
    " The oracle picks by true benefit "
    "(outcomes and errors it could not know), greedily among a few increments per step: a "
    "lower bound on what choosing runs can gain, not a ceiling. Its "
    "control chooses the same way among uniform draws only: what a best-of-k choice gains "
    "from the spread of small-data monitors alone. The oracle's gain over its control is what "
    "choosing the kind of run adds.")
MODE_WORDS = {"pool": "picked from a pool of pre-simulated uniform runs",
              "generative": "simulating what it proposes"}


def _label(name: str) -> str:
    return {ORACLE: "oracle (lower bound)", ORACLE_UNIFORM: "oracle-uniform (its control)",
            ORACLE_SEEDS: "oracle-seeds (its best-of-k-seeds control)",
            QBC: "qbc (pool-mode diagnostic)", REFERENCE: "uniform (reference)"}.get(name, name)


def _efficiency(e: dict | None) -> str:
    if not e or e.get("factor") is None:
        return "–"
    return f"{'> ' if e['censored'] else ''}{e['factor']:.2f} [{e['low']:.2f}, {e['high']:.2f}]"


def curve_table(summary: dict) -> list[str]:
    """Mean [95 % CI] per budget, the area, and each strategy against Uniform."""
    budgets = summary["reference_budgets"]
    header = ["strategy", *(f"{b} runs" for b in budgets), "area", f"area {chr(8722)} Uniform",
              f"final {chr(8722)} Uniform", "Uniform's budget ×"]
    rows = []
    for name, s in summary["strategies"].items():
        cells = [mean_cell(m, "auprc", m["n"]) for m in s["mean"]]
        cells += [""] * (len(budgets) - len(cells))
        vs = s.get("area_vs_reference")
        rows.append([_label(name), *cells, mean_cell(s["area"], "auprc", s["area"]["n"]),
                     diff_cell(vs) if vs else "", diff_cell(s["final_vs_reference"]) if vs
                     else "", _efficiency(s.get("efficiency"))])
    lines = md_table(header, rows)
    oracle = summary["strategies"].get(ORACLE, {})
    for suffix, words in (("control", "its uniform-only control"),
                          ("seeds", "its best-of-k-training-seeds control")):
        if vs := oracle.get(f"area_vs_{suffix}"):
            lines += ["", f"Oracle {chr(8722)} {words}: area {diff_cell(vs)}, "
                          f"final {diff_cell(oracle[f'final_vs_{suffix}'])}."]
    return lines


def detectable_table(summary: dict) -> list[str]:
    """Per strategy, the paired MDE against Uniform (80 % power, two-sided α 0.05, paired t)
    over the seeds run, on the area and at each checkpoint, with the differences' SD."""
    keys = ["area", *map(str, summary["budgets"][1:])]

    def cell(d: dict | None) -> str:
        if not d or d["mde"] is None:
            return "–"
        return f"{100 * d['mde']:.1f} (SD {100 * d['sd_diff']:.1f}, n = {d['n']})"

    rows = [[_label(name), *(cell(s["detectable"].get(k)) for k in keys)]
            for name, s in summary["strategies"].items() if "detectable" in s]
    return md_table(["strategy", *(k if k == "area" else f"{k} runs" for k in keys)], rows)


def found_table(found: dict[str, dict]) -> list[str]:
    """Per strategy and checkpoint, the collisions per 100 runs acquired [95 % CI over seeds],
    and Uniform's multiple."""
    budgets = list(found)
    names = list(dict.fromkeys(n for b in budgets for n in found[b]))

    def cell(f: dict | None) -> str:
        if not f or f["per_run"]["value"] is None:
            return "–"
        r = f["per_run"]
        text = f"{PER * r['value']:.1f}"
        if r["low"] is not None:
            text += f" [{PER * r['low']:.1f}, {PER * r['high']:.1f}]"
        ratio = f.get("vs_reference", {}).get("ratio")
        return text + (f" ×{ratio:.2f}" if ratio is not None else "")

    rows = [[_label(n), *(cell(found[b].get(n)) for b in budgets)] for n in names]
    return md_table(["strategy", *(f"by {b} runs" for b in budgets)], rows)


def rates_table(rates: dict[str, dict]) -> list[str]:
    """Per strategy with an unbiased estimate of P(collision) under p and checkpoint: the mean
    estimate over seeds (%), its spread over seeds / mean, and that spread's ratio to Uniform's
    at the same budget."""
    budgets = list(rates)
    names = list(dict.fromkeys(n for b in budgets for n in rates[b]))

    def cell(r: dict | None) -> str:
        if not r:
            return "–"
        text = f"{100 * r['mean']:.2f} %"
        if r["spread"] is not None:
            text += f" (±{r['spread']:.2f})"
        ratio = (r.get("vs_reference") or {}).get("spread")
        return text + (f" ×{ratio:.2f}" if ratio is not None else "")

    rows = [[_label(n), *(cell(rates[b].get(n)) for b in budgets)] for n in names]
    return md_table(["strategy", *(f"by {b} runs" for b in budgets)], rows)


def where_table(where: dict) -> list[str]:
    """Per strategy, where its acquired runs fell (the mean over seeds at its last common
    budget): the share that collided, then the safe ones by their smallest gap to another
    road user."""
    edges = ["0", *(f"{e:g}" for e in MARGIN_BINS_M)]
    bins = [f"gap {a}–{b} m" for a, b in zip(edges[:-1], edges[1:], strict=True)]
    rows = [[_label(name), f"{w['runs']:.0f}", pct(w["collided"]),
             *(pct(v) for v in w["by_gap"])] for name, w in where.items()]
    return md_table(["strategy", "acquired runs", "collided (%)", *(f"{b} (%)" for b in bins),
                f"gap ≥ {edges[-1]} m (%)"], rows)


def chart(summary: dict, title: str) -> str:
    """The learning curves with their 95 % bands, in points."""
    series = []
    for name, s in summary["strategies"].items():
        def col(key: str, s=s) -> list[float]:
            return [float("nan") if m[key] is None else 100 * m[key] for m in s["mean"]]

        series.append((_label(name), summary["reference_budgets"][: len(s["mean"])],
                       col("mean"), col("low"), col("high")))
    return band_chart(series, title=title, xlabel="runs (log scale)", ylabel="AUPRC (%)")


def regime_markdown(regime: str, result: dict) -> str:
    """One regime's section: its sets, a table per summary, where each strategy sampled."""
    scenario, profile = parse_regime(regime)
    sets = result["sets"]
    lines = [f"## {scenario}, {profile} ADS", "",
             f"Pool: {sets['pool']['runs']} uniform runs, {sets['pool']['collisions']} of them "
             f"collide. Test Set: {sets['test']['runs']} runs ({sets['test']['frames']:,} "
             f"frames, {sets['test']['unsafe']:,} unsafe). Boundary set: "
             f"{sets['boundary']['runs']} runs. Validation: {sets['val']['runs']} runs. "
             f"Oracle set: {sets['oracle']['runs']} runs.", ""]
    for key, summary in result["summaries"].items():
        set_name, kind = key.split("/")
        lines += [f"### AUPRC on {SET_WORDS[set_name]}: {KIND_WORDS[kind]}", "",
                  *curve_table(summary), ""]
        if key == "test/scratch":
            lines += ["Minimum detectable effect against Uniform (points; 80 % power, two-sided "
                      "α 0.05, paired t over these seeds): a difference smaller than it is not "
                      "shown either way.", "", *detectable_table(summary), ""]
    lines += ["### Where each strategy sampled", "", *where_table(result["where"]), ""]
    if result.get("found"):
        lines += ["### Failures found", "", "Collisions per 100 runs acquired beyond the initial "
                  "set [95 % CI, bootstrap over seeds] and the multiple of Uniform's (in "
                  "generative mode a run acquired is a run simulated; the oracle and its "
                  "control trained on several increments per step and kept one"
                  + ("; oracle-seeds's runs are Uniform's" if ORACLE_SEEDS in result["where"]
                     else "") + ").", "",
                  *found_table(result["found"]), ""]
    if result.get("rates"):
        lines += ["### The failure rate under p", "", "The unbiased estimate of P(collision) "
                  "each strategy's acquired runs give (Uniform: the share that collided; "
                  "ce-is: weighted by their exact p/q), its mean over seeds, (± its SD over "
                  "seeds / the mean: the relative error the seeds show) and that relative "
                  "error's multiple of Uniform's at the same budget.", "",
                  *rates_table(result["rates"]), ""]
    if result.get("failed"):
        lines += ["### Curves that failed", "", "Left out of every table above; a re-run of the "
                  "same command retries them alone.", "",
                  *(f"* {f['strategy']}, seed {f['seed']}: {f['error']}"
                    for f in result["failed"]), ""]
    return "\n".join(lines)


def efficiency_markdown(efficiency: dict) -> str:
    """efficiency.md: the intro, then every regime."""
    cfg = efficiency["config"]
    intro = INTRO.format(initial=cfg["initial_runs"], n_round=cfg["n_round"],
                         mode=MODE_WORDS[cfg["mode"]],
                         budgets=", ".join(map(str, cfg["checkpoints"])),
                         seeds=f"{cfg['seeds'][0]}–{cfg['seeds'][-1]}")
    shown = {n for r in efficiency["regimes"].values()
             for n in r["summaries"]["test/scratch"]["strategies"]}
    intro += (ORACLE_WORDS if ORACLE in shown else "") + learner_words(cfg)
    intro += curve_words(cfg, shown)
    body = [regime_markdown(r, result) for r, result in efficiency["regimes"].items()]
    return "\n".join(["# Sample efficiency: does choosing runs teach the monitor faster?", "",
                      "Generated by `evoeye results --part efficiency`. " + intro, "",
                      *body])


def learner_words(cfg: dict) -> str:
    """What the checkpoint monitors and their validation set were, where they differ from one
    monitor on the uniform validation batch (nothing then: such pages read as they did)."""
    out = ""
    if (k := cfg.get("members", 1)) > 1:
        out += (f" Each checkpoint's monitor is an ensemble of {k} members trained from scratch "
                "on the same runs (member 0 with the checkpoint's training seed, the others "
                "with seeds derived from it), scored by their mean risk and calibrated on the "
                "validation set as one monitor.")
    if n := cfg.get("val_collisions", 0):
        out += (f" The validation set holds at least {n} colliding runs: the uniform batch and "
                "the unsafe windows of further runs of its seed stream that collided (its "
                "negatives, which calibrate the thresholds, are the uniform batch's).")
    return out


def curve_words(cfg: dict, shown: set[str]) -> str:
    """What the curves beyond the strategies' are, where a study has them (nothing for a study
    without them, e.g. run with --no-oracle)."""
    out = ""
    if cfg.get("oracle_step", "checkpoint") == "round" and ORACLE in shown:
        out += (f" The oracle chooses an increment every round of {cfg['n_round']} runs, each "
                "from the monitor the last round kept, rather than once per checkpoint.")
    if ORACLE_SEEDS in shown:
        out += (" The oracle's other control (oracle-seeds) chooses no runs: at each checkpoint "
                "it trains monitors on Uniform's own runs with "
                f"{cfg['oracle_candidates']} training seeds and keeps the best on the "
                "oracle set, what picking the luckiest training seed alone gains; the oracle's "
                "gain over it is what choosing runs adds.")
    if QBC in shown:
        out += (" qbc is query-by-committee on the unused pool runs' own windows (a committee "
                "trained from scratch every round; the runs it disagrees on most): a pool-mode "
                "diagnostic of what `disagreement` loses by predicting disagreement over θ, "
                "not a strategy that could choose a run before simulating it.")
    return out


def efficiency_findings_markdown(findings: list[dict]) -> str:
    """The study's claims, their verdicts and their checks (for findings.md)."""
    out = ["### Does acquisition earn its budget?", "",
           *md_table(["claim", "verdict"], [[f["claim"], f"**{f['verdict']}**"] for f in findings],
                numbers=False), ""]
    for f in findings:
        if f["checks"]:
            rows = [[c["regime"], c["strategy"], c.get("against", REFERENCE),
                     diff_cell(c["area"]), c["area_verdict"],
                     _efficiency(c["efficiency"]), c["efficiency_verdict"]]
                    for c in f["checks"]]
            out += [f"**{f['claim']}** — {f['verdict']}", "",
                    *md_table(["regime", "strategy", "against",
                               "area difference [95 % CI] p",
                          "verdict", "Uniform's budget ×", "verdict"], rows, numbers=False),
                    ""]
    return "\n".join(out)


def efficiency_html(efficiency: dict) -> list[str]:
    """The study's part of results.html: per regime, a chart of each summary's curves."""
    out = ["<h2>Sample efficiency</h2>"]
    for regime, result in efficiency["regimes"].items():
        scenario, profile = parse_regime(regime)
        out.append(f"<h3>{escape(scenario)}, {escape(profile)} ADS</h3>")
        for key, summary in result["summaries"].items():
            set_name, kind = key.split("/")
            out.append(chart(summary, f"{SET_WORDS[set_name]}, {kind}"))
    return out


def study_words(cfg: dict) -> str:
    """What a study run was, in a few words: its mode and seeds (per regime when a study's
    regimes ran with seeds of their own, `merge_studies`)."""
    def seeds_words(seeds: list[int]) -> str:
        return f"{len(seeds)} seeds ({seeds[0]}–{seeds[-1]})"

    seeds = cfg["seeds"]
    if isinstance(seeds, dict):
        return (f"{MODE_WORDS[cfg['mode']]}, regimes "
                + ", ".join(f"{r} ({seeds_words(s)})" for r, s in seeds.items()))
    return (f"{MODE_WORDS[cfg['mode']]}, {seeds_words(seeds)}, "
            f"regimes {', '.join(cfg['regimes'])}")
