"""The RQ2 report: tables (mean ± sample SD over seeds), the last round's means with their 95 %
CIs as error bars, per-round curves and the blind-spot map.

Input is `collect_results`' dict ({scenario: {"initial", "aem-initial", method: [runs]}}); output
Markdown, self-contained HTML (SVG charts) and the JSON under `<root>/reports/<name>/`.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from datetime import UTC, datetime
from html import escape
from pathlib import Path

import numpy as np

from evoeye.evaluation.plots import interval_chart, line_chart
from evoeye.evaluation.report import CSS
from evoeye.evaluation.stats import finite_mean, mean_ci, sample_sd
from evoeye.evaluation.table import DASH, UNREACHABLE, UNREACHABLE_NOTE, Table, pct
from evoeye.evolve.campaign.assess import reached
from evoeye.evolve.campaign.experiment import ABLATION, MAIN, methods
from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES
from evoeye.paths import DataRoot
from evoeye.store.feedback import RoundRow

COLUMNS = ("f1@0.05", "f1@0.01", "auroc", "auprc")
ACQUISITION_HEAD = ("Method", "Runs", "Collisions %", "Near misses %", "Within δ %", "f %")
ACQUISITION_NOTE = ("Near misses: collision-free runs whose footprints came within 1 m. Within "
                    "δ: runs within δ (Chebyshev, normalised) of an earlier record. f: mean "
                    "feedback |ŷ − y| under the monitor that chose the run, in %.")
SETS = (("Test", "the Test Set"), ("Hard", "the Hard Set of G_0"))
TITLE = "Self-evolution under the same simulation budget (RQ2)"


OTHER_SCALE = " ²"  # marks a `<family>-evo` row: its f is on its own monitor's score scale
OTHER_SCALE_NOTE = ("² its f is |score − label| under its own family's monitor: the AEM scores "
                    "a typical window near 0.5 (e / (e + ẽ)), so its f is not comparable with "
                    "the FusionMonitor methods'.")


def ran(res: dict) -> tuple[str, ...]:
    """The methods with runs in `res`: the RQ2 ones, the ablations, then any other."""
    return tuple(m for m in dict.fromkeys(MAIN + ABLATION + tuple(methods())) if res.get(m))


def tables(res: dict) -> tuple[tuple[str, tuple[str, ...]], ...]:
    """(title, methods) of each table: RQ2 (with methods that are neither RQ2 nor ablation),
    and the evolution ablation."""
    other = tuple(m for m in ran(res) if m not in MAIN + ABLATION)
    return (("Acquisition methods compared (RQ2)", MAIN + other),
            ("Evolution ablation", ("evoeye",) + ABLATION))


def own_initial(method: str) -> tuple[str, str] | None:
    """(row label, results key) of a method's starting monitor when it is not the FusionMonitor
    G_0 (a `<family>-evo` method starts from its family's G_0)."""
    family = methods().get(method, ("", DEFAULT_FAMILY))[1]
    if family == DEFAULT_FAMILY:
        return None
    label = FAMILIES[family].label
    return f"{label} ({label}-Evo's G_0)", f"{family}-initial"


def other_scale(method: str) -> bool:
    """Whether a method's feedback is on another family's score scale: it evolves another
    family's monitor (a `<family>-evo`, `own_initial`)."""
    return own_initial(method) is not None


def _value(v: float | None) -> float:
    """A metric as a float; None (undefined, e.g. AUPRC with one class) becomes NaN."""
    return np.nan if v is None else float(v)


def _mean_std(values: list[float | None], reachable: Sequence[bool] | None = None) -> str:
    """Mean ± sample SD (in %) of one figure's finite values over seeds ('–' if there is none);
    seeds whose target FPR was unreachable are left out and counted ('n/r' if every seed's
    was)."""
    a = np.asarray(values, float)
    if not len(a):
        return DASH
    ok = np.ones(len(a), bool) if reachable is None else np.asarray(reachable, bool)
    if not ok.any():
        return UNREACHABLE
    a = a[ok]
    mean, sd = finite_mean(a), sample_sd(a)
    if mean is None:  # no seed's figure is defined, e.g. AUROC on a one-class set
        cell = DASH
    else:  # one seed has no spread to report: "± 0.0" would read as zero variance
        cell = f"{100 * mean:.1f}" + ("" if sd is None else f" ± {100 * sd:.1f}")
    return cell if ok.all() else f"{cell} ({int((~ok).sum())}/{len(ok)} {UNREACHABLE})"


def _cells(per_seed: Sequence[dict]) -> list[str]:
    """Mean ± sample SD over seeds of every column on the Test Set and the Hard Set, from each
    seed's {"test": metrics, "hard": metrics} (`Assessor`'s)."""
    cells = []
    for split in ("test", "hard"):
        for col in COLUMNS:
            ms = [m[split] for m in per_seed]
            cells.append(_mean_std([_value(m[col]) for m in ms], [reached(m, col) for m in ms]))
    return cells


def table_rows(res: dict, strategies: Sequence[str]) -> list[list[str]]:
    """Rows: method (those that ran), then mean ± sample SD (in %) of each column on the Test
    Set and the Hard Set."""
    rows = [["initial (G_0)", *_cells([res["initial"]])]] if res.get("initial") else []
    if res.get("reseeded"):
        rows.append([f"G_0 re-seeded ×{len(res['reseeded'])} (no new data)",
                     *_cells(res["reseeded"])])
    for strategy in strategies:
        if (own := own_initial(strategy)) and res.get(own[1]):
            label, key = own
            rows.append([label, *_cells([res[key]])])
        runs = res.get(strategy, [])
        if not runs:  # not part of this experiment
            continue
        rows.append([strategy, *_cells([r["rounds"][-1] for r in runs])])
    return rows


def acquisition_rows(res: dict) -> list[list[str]]:
    """Per strategy: acquired runs, collision, near-miss and near-record shares, and the mean
    feedback under the monitor that chose the runs (mean ± sample SD over seeds)."""
    rows = []
    for strategy in ran(res):
        acq = [r["acquisition"] for r in res.get(strategy, []) if r.get("acquisition")]
        if acq:
            runs = np.array([a["runs"] for a in acq], float)
            sd = sample_sd(runs)
            runs_s = f"{runs.mean():.0f}" + ("" if sd is None else f" ± {sd:.0f}")
            rows.append([strategy + (OTHER_SCALE if other_scale(strategy) else ""), runs_s,
                         _mean_std([a["collision_share"] for a in acq]),
                         _mean_std([a.get("near_miss_share", np.nan) for a in acq]),
                         _mean_std([a["near_share"] for a in acq]),
                         _mean_std([a.get("feedback") for a in acq])])
    return rows


def _has_unreachable(results: dict) -> bool:
    return any(UNREACHABLE in cell for res in results.values() for _, strategies in tables(res)
               for row in table_rows(res, strategies) for cell in row)


def set_tables(rows: list[list[str]]) -> list[tuple[str, Table]]:
    """`table_rows`' rows as one narrow table per set (Test, Hard): method and COLUMNS."""
    head = ["Method"] + [c.replace("@0", "@").upper() + " %"
                         for c in COLUMNS]
    n = len(COLUMNS)
    return [(name, Table(head, [[r[0], *r[1 + i * n:1 + (i + 1) * n]] for r in rows]))
            for i, (_, name) in enumerate(SETS)]


def _sections(results: dict):
    """(heading, note, table) of every table of the report, in order."""
    for scenario, res in results.items():
        for title, strategies in tables(res):
            for name, table in set_tables(table_rows(res, strategies)):
                yield (f"{scenario}: {title}, on {name}",
                       "Last round; mean ± sample SD over seeds, in %.", table)
        acquired = acquisition_rows(res)
        note = ACQUISITION_NOTE + (" " + OTHER_SCALE_NOTE
                                   if any(r[0].endswith(OTHER_SCALE) for r in acquired) else "")
        yield (f"{scenario}: what each method acquired", note + " Mean ± sample SD over seeds.",
               Table(list(ACQUISITION_HEAD), acquired))


def markdown(results: dict) -> str:
    out = [f"# {TITLE}", ""]
    if _has_unreachable(results):
        out += [UNREACHABLE_NOTE, ""]
    for heading, note, table in _sections(results):
        out += [f"## {heading}", "", note, "", table.markdown(), ""]
    return "\n".join(out)


def _curves(res: dict, split: str, col: str) -> str:
    series = []
    by_method = {s: res[s] for s in ran(res)}
    n_max = max((len(r["rounds"]) for runs in by_method.values() for r in runs), default=1)
    for strategy, runs in by_method.items():
        n = min(len(r["rounds"]) for r in runs)
        # a round's point: the mean of its finite values; a gap (NaN) when none is, e.g. an
        # F1 whose FPR no seed's thresholds reached
        ys = [_value(finite_mean([_value(r["rounds"][i][split][col]) for r in runs]))
              for i in range(n)]
        series.append((strategy, [i / max(n_max - 1, 1) for i in range(n)], ys))
    return line_chart(series, title=f"{split} {col} per round", xlabel="round (0 … last)",
                      ylabel=col)


def _intervals(res: dict, split: str, col: str) -> str:
    """Each method's last-round mean over seeds with its 95 % t interval, as error bars."""
    rows = []
    for method in ran(res):
        ci = mean_ci([_value(r["rounds"][-1][split][col]) for r in res[method]])
        rows.append((method, *(None if v is None else 100 * v
                               for v in (ci.mean, ci.low, ci.high))))
    return interval_chart(rows, title=f"{split} {col}, last round: mean, 95 % CI",
                          xlabel=f"{col} (%)")


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


def html(results: dict) -> str:
    body = [f"<h1>{escape(TITLE)}</h1>"]
    if _has_unreachable(results):
        body.append(f"<p>{escape(UNREACHABLE_NOTE)}</p>")
    sections = list(_sections(results))
    for scenario, res in results.items():
        body.append(f"<h2>{escape(scenario)}</h2>")
        for heading, note, table in sections:
            if heading.startswith(f"{scenario}: "):
                body.append(f"<h3>{escape(heading.split(': ', 1)[1])}</h3>"
                            f"<p>{escape(note)}</p>{table.html()}")
        for split in ("test", "hard"):
            for col in ("f1@0.05", "auprc"):
                body += [_intervals(res, split, col), _curves(res, split, col)]
        spots = [r["blind_spots"] for r in res.get("evoeye", []) if r.get("blind_spots")]
        if spots:
            body.append("<h3>Blind-spot map (EvoEye, first seed)</h3>" + _scatter(spots[0]))
    return (f"<!doctype html><meta charset=utf-8><title>evoeye: {escape(TITLE)}</title>"
            f"<style>{CSS}</style><body>" + "".join(body) + "</body>")


def write_experiment_report(root: DataRoot, results: dict,
                            name: str | None = None) -> Path:
    """rq2.md, rq2.html and rq2.json under `<root>/reports/<name>/`; the folder."""
    folder = root.reports / (name or f"rq2-{datetime.now(UTC):%Y%m%dT%H%M%SZ}")
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "rq2.md").write_text(markdown(results), encoding="utf-8")
    (folder / "rq2.html").write_text(html(results), encoding="utf-8")
    (folder / "rq2.json").write_text(json.dumps(results, indent=1, default=float),
                                     encoding="utf-8")
    return folder


def _rate(split: dict | None, key: str) -> str:
    """A round's rate in % ('–' if not assessed, 'n/r' where its target FPR was unreachable)."""
    if split is None:
        return DASH
    return pct(split[key]) if reached(split, key) else UNREACHABLE


def rounds_table(rows: Sequence[RoundRow]) -> Table:
    """A campaign round by round: new runs, simulated time so far, and its monitor G_r on the
    Test Set and on G_0's Hard Set (%)."""
    out = []
    for r in rows:
        m = r.metrics
        out.append([str(r.round), str(len(r.scenario_ids)), f"{r.simulated_s:.0f}",
                    r.monitor_version, _rate(m and m.test, "f1@0.05"),
                    _rate(m and m.test, "auprc"), _rate(m and m.hard, "f1@0.05")])
    return Table(["Round", "New runs", "Sim s", "Monitor", "Test F1@.05 %", "Test AUPRC %",
                  "Hard F1@.05 %"], out)


def rounds_markdown(rows: Sequence[RoundRow]) -> str:
    """A campaign's artifact: what it is, the rounds table, and what the last round changed."""
    if not rows:
        return "# Evolution\n\nNo round stored yet."
    first = rows[0]
    head = (f"# Evolution: {first.logical_scenario}, {first.strategy}, seed {first.seed}\n\n"
            f"Campaign `{first.campaign_id}`: {len(rows) - 1} round(s) after G_0.")
    return "\n\n".join([head, rounds_table(rows).markdown(), change_words(rows)])


G0_WORDS = "the monitor the campaign started from"


def change_words(rows: Sequence[RoundRow]) -> str:
    """What evolution changed, G_0 to the last round's monitor, in words (with the sizes the
    figures rest on)."""
    if len(rows) < 2:
        return "No acquisition round yet: the monitor is still G_0."
    g0, last = rows[0], rows[-1]
    new = sum(len(r.scenario_ids) for r in rows[1:])
    kept = last.monitor_version == g0.monitor_version
    why = ("no round acquired a run to learn from" if not new else
           "no update beat it on the validation split")
    g0_is = f"G_0 {g0.monitor_version} ({G0_WORDS}"
    text = (f"{len(rows) - 1} round(s) added {new} runs ({last.simulated_s - g0.simulated_s:.0f}"
            f" s simulated) and " + (f"kept {g0_is}; kept: {why})" if kept else
                                     f"replaced {g0_is}) by {last.monitor_version}"))
    a, b = g0.metrics, last.metrics
    if kept:  # the same monitor: its figures are G_0's
        return text + "."
    if a is None or b is None:
        return text + " (not assessed: run with --assess to see its effect)."
    return (f"{text}: Test-Set F1@0.05 {_rate(a.test, 'f1@0.05')} → {_rate(b.test, 'f1@0.05')} "
            f"%, Hard-Set F1@0.05 {_rate(a.hard, 'f1@0.05')} → {_rate(b.hard, 'f1@0.05')} % "
            f"(the Hard Set: the {a.hard.get('unsafe', 0)} unsafe test frames G_0 missed and "
            f"the safe frames of their runs, {a.hard.get('frames', 0)} in all). One campaign "
            "seed, frame-level figures: a change this size can come from retraining alone; "
            "`evoeye experiment` compares methods over seeds, with a re-seeded G_0 as control.")
