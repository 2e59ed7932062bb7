"""Warn in time to act (issue 37): FusionMonitor variants against today's, by the open-loop
deployment proxy on the validation runs (`experiments.lead_proxy`).

    python -m experiments.lookahead train --root R --variant v3 --seed 0
    python -m experiments.lookahead rescore --root R --variants v3,L40,... --seeds 0,1
    python -m experiments.lookahead table --root R --variants v3,L40,... --seeds 0 \\
        [--reference v3] [--n-boot 1000] [--json OUT.json] [--md OUT.md]

The data root holds round-0 runs of highway-cut-in (e.g. `evoeye simulate --scenario
highway-cut-in --n 1600 --seed 9101`) and a held-out test batch never read here (`--test-batch`,
default test-seed9103, kept for the closed-loop supervisor). The other runs split by run,
`--train-frac` / `--val-frac` (default 0.5 / 0.5: a large validation split, since the proxy
counts colliding runs and false alarms per hour). `train` trains one variant (VARIANTS: a
recipe, its overrides, L) with `train_monitor` — a saved version the supervisor can load —
scores the validation windows (logits: float32 risks saturate at 1.0, and the supervisor
thresholds logits) and keeps them and the training's CPU seconds under
R/experiments/lookahead/ (`rescore` scores them again with the saved versions). `table` reads
them back and prints, per variant and seed, the proxy at ≤ 1 and ≤ 5 false alarms per hour with
bootstrap CIs and the paired difference from the reference, under two counts of false alarms
(`FA_KINDS`), and the frame metrics (labels always H = 3 s, whatever a variant trained on).
Choose on validation only: the test batch is for the supervisor.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from experiments.lead_proxy import ValRuns, frame_metrics, proxy_table

SCENARIO = "highway-cut-in"
H_S = 3.0
ORACLE = "GT required decel"  # `--oracles`: the ground truth's required deceleration, m/s²
# name → how it trains: recipe, TrainParams overrides, context length L, label horizon
VARIANTS: dict[str, dict[str, Any]] = {
    "v3": {"recipe": "v3"},  # today's FusionMonitor: L = 5, AUPRC, every unsafe window
    "L20": {"recipe": "v3", "context_len": 20},
    "L40": {"recipe": "v3", "context_len": 40},
    "pauc": {"recipe": "v3", "select_on": "pauc"},
    "lead0.5": {"recipe": "v3", "min_lead_s": 0.5},
    "lead1": {"recipe": "v3", "min_lead_s": 1.0},
    "H4": {"recipe": "v3", "horizon_s": 4.0},
    "H5": {"recipe": "v3", "horizon_s": 5.0},
    "nm-ignored": {"recipe": "v3", "near_misses": "ignored"},
    "nm-unsafe": {"recipe": "v3", "near_misses": "unsafe"},
    "L40+nm-unsafe": {"recipe": "v3", "context_len": 40, "near_misses": "unsafe"},
    "L20+nm-unsafe": {"recipe": "v3", "context_len": 20, "near_misses": "unsafe"},
    "L40+pauc": {"recipe": "v3", "context_len": 40, "select_on": "pauc"},
    "L40+lead0.5": {"recipe": "v3", "context_len": 40, "min_lead_s": 0.5},
    "L40+pauc+lead0.5": {"recipe": "v3", "context_len": 40, "select_on": "pauc",
                         "min_lead_s": 0.5},
}


def splits(args: argparse.Namespace):
    from evoeye.store import SplitSpec

    return SplitSpec(seed=args.split_seed, train_frac=args.train_frac, val_frac=args.val_frac,
                     test_batch=args.test_batch)


def out_dir(root: str) -> Path:
    path = Path(root) / "experiments" / "lookahead"
    path.mkdir(parents=True, exist_ok=True)
    return path


def val_windows(args: argparse.Namespace, context_len: int):
    from evoeye.paths import DataRoot
    from evoeye.store.selection import RunFilter
    from evoeye.store.windows import load_windows

    runs = RunFilter(logical_scenario=SCENARIO, split="val", splits=splits(args))
    return load_windows(DataRoot.existing(args.root), runs, context_len=context_len,
                        horizon_s=H_S)


def train(args: argparse.Namespace) -> None:
    """Train one variant at one seed, score the validation windows, keep both."""
    from evoeye.monitor.registry import load_monitor, read_card
    from evoeye.monitor.train import train_monitor
    from evoeye.paths import DataRoot

    spec = dict(VARIANTS[args.variant])
    recipe, L = spec.pop("recipe"), spec.pop("context_len", 5)
    horizon = spec.pop("horizon_s", H_S)
    root = DataRoot.existing(args.root)
    c0, t0 = time.process_time(), time.perf_counter()
    version = train_monitor(root, SCENARIO, context_len=L, horizon_s=horizon, seed=args.seed,
                            splits=splits(args), recipe=recipe, **spec)
    cpu_total, wall = time.process_time() - c0, time.perf_counter() - t0
    card = read_card(root, version)
    val = val_windows(args, L)
    stem = out_dir(args.root) / f"{args.variant}-s{args.seed}"
    np.save(stem.with_suffix(".npy"), load_monitor(root, version).logits(val))
    record = {"variant": args.variant, "seed": args.seed, "version": version,
              "spec": VARIANTS[args.variant], "cpu_s": card["training"]["cpu_s"],
              "process_cpu_s": round(cpu_total, 1), "wall_s": round(wall, 1),
              "best_epoch": card["training"]["best_epoch"],
              "n_parameters": card["n_parameters"], "val_windows": len(val),
              "val_frames_sha": _frames_key(val)}
    stem.with_suffix(".json").write_text(json.dumps(record, indent=1), encoding="utf-8")
    print(json.dumps(record))


def rescore(args: argparse.Namespace) -> None:
    """Score the validation windows again with every (variant, seed) version trained."""
    from evoeye.monitor.registry import load_monitor
    from evoeye.paths import DataRoot

    root = DataRoot.existing(args.root)
    for seed in args.seeds:
        for variant in args.variants:
            stem = out_dir(args.root) / f"{variant}-s{seed}"
            if not stem.with_suffix(".json").exists():
                continue
            record = json.loads(stem.with_suffix(".json").read_text(encoding="utf-8"))
            monitor = load_monitor(root, record["version"])
            val = val_windows(args, monitor.context_len)
            np.save(stem.with_suffix(".npy"), monitor.logits(val))
            record["val_frames_sha"] = _frames_key(val)
            stem.with_suffix(".json").write_text(json.dumps(record, indent=1), encoding="utf-8")


def _frames_key(windows) -> str:
    import hashlib

    h = hashlib.sha256(windows.frame.tobytes())
    h.update("\n".join(windows.scenario_id.tolist()).encode())
    return h.hexdigest()[:16]


def collision_times(args: argparse.Namespace) -> dict[str, float]:
    from evoeye.paths import DataRoot
    from evoeye.store.catalog import Warehouse

    con = Warehouse(DataRoot.existing(args.root)).connect()
    try:
        rows = con.sql("SELECT scenario_id, min(collision_time_s) FROM eligible_frames "
                       "WHERE collision_time_s IS NOT NULL GROUP BY scenario_id").fetchall()
    finally:
        con.close()
    return dict(rows)


def justified_frames_of(args: argparse.Namespace, val) -> np.ndarray:
    """(B,) bool: an alarm at the window's frame is *justified* as the supervisor judges an
    intervention (`evoeye.criticality`: labelled 1, or the run comes
    critically close within H — ground-truth TTC-2D < 1.5 s or a required deceleration
    > 4 m/s²), from every actor's ground truth in the run's log. Cached beside the scores."""
    from evoeye.criticality import (
        Criticality,
        frame_risk,
        justified_frames,
    )
    from evoeye.log.channels import TOPICS, ground_truth_scene
    from evoeye.log.reader import read_run

    cache = out_dir(args.root) / f"justified-{_frames_key(val)}.npz"
    if cache.exists():
        return np.load(cache)["justified"]
    out = np.zeros(len(val), bool)
    ttc, decel = np.zeros(len(val)), np.zeros(len(val))  # ground truth, for oracle triggers
    sid = val.scenario_id
    start = np.flatnonzero(np.r_[True, sid[1:] != sid[:-1]])
    logs = {p.stem: p for p in (Path(args.root) / "runs" / SCENARIO).glob("*/*.mcap")}
    for lo, hi in zip(start, np.append(start[1:], len(sid)), strict=True):
        scenes = [ground_truth_scene(m) for _, m in read_run(
            logs[sid[lo]], [TOPICS.ground_truth]).messages(TOPICS.ground_truth)]
        risk = frame_risk(scenes)
        out[lo:hi] = justified_frames(val.label[lo:hi], risk.critical(Criticality()),
                                      int(round(H_S / 0.05)))
        ttc[lo:hi], decel[lo:hi] = risk.ttc_s[: hi - lo], risk.decel_mps2[: hi - lo]
    np.savez(cache, justified=out, gt_ttc_s=ttc, gt_required_decel_mps2=decel)
    return out


def table(args: argparse.Namespace) -> dict[str, Any]:
    """The proxy and frame metrics of every (variant, seed) trained, as a dict and Markdown."""
    val = val_windows(args, 1)  # the frames and their order; L does not change them
    runs = ValRuns.of(val.scenario_id, val.t_s, collision_times(args), H_S)
    assert np.array_equal(runs.label, val.label == 1), "labels differ from the warehouse's"
    calm = replace(runs, justified=justified_frames_of(args, val) & ~runs.label)
    key = _frames_key(val)
    scores, records = {}, {}
    for seed in args.seeds:
        for variant in args.variants:
            stem = out_dir(args.root) / f"{variant}-s{seed}"
            if not stem.with_suffix(".json").exists():
                continue  # not trained at this seed
            record = json.loads(stem.with_suffix(".json").read_text(encoding="utf-8"))
            if record["val_frames_sha"] != key:
                raise SystemExit(f"{stem}: scored on other validation windows")
            name = f"{variant} s{seed}"
            scores[name], records[name] = np.load(stem.with_suffix(".npy")), record
    if args.oracles:  # ground-truth physics as a trigger: what no monitor can beat
        gt = np.load(out_dir(args.root) / f"justified-{key}.npz")
        for seed in args.seeds[:1]:
            name = f"{ORACLE} s{seed}"
            scores[name] = gt["gt_required_decel_mps2"]
            records[name] = {"seed": seed, "cpu_s": 0.0}
    ref_of = {name: f"{args.reference} s{records[name]['seed']}" for name in scores}
    result: dict[str, Any] = {"val_runs": len(runs.run_start),
                              "colliding_runs": len(np.unique(runs.run[runs.label])),
                              "safe_h": float((~runs.label).sum() * runs.dt_s / 3600),
                              "calm_h": float((~runs.label & ~calm.justified).sum()
                                              * runs.dt_s / 3600),
                              "rows": {}}
    for seed in args.seeds:
        group = {n: s for n, s in scores.items() if records[n]["seed"] == seed}
        proxy = {fa: proxy_table(group, r, reference=f"{args.reference} s{seed}",
                                 n_boot=args.n_boot, seed=args.boot_seed)
                 for fa, r in (("label", runs), ("calm", calm))}
        for name in group:
            result["rows"][name] = {"record": records[name], "reference": ref_of[name],
                                    "frame": frame_metrics(group[name], runs.label),
                                    **{f"proxy_{fa}": p[name] for fa, p in proxy.items()}}
    return result


FA_KINDS = {"label": "false alarms: onsets at frames labelled safe, per hour of them",
            "calm": "unneeded alarms (the supervisor's false interventions, open loop): onsets "
                    "at safe frames with no critical approach within H, per hour of them"}


def markdown(result: dict[str, Any]) -> str:
    return "\n\n".join(markdown_kind(result, kind) for kind in FA_KINDS)


def markdown_kind(result: dict[str, Any], kind: str) -> str:
    def ci(row: dict, key: str, diff: bool = False) -> str:
        lo, hi = row["diff_ci" if diff else "ci"][key]
        sign = "+" if diff else ""
        return f"[{lo:{sign}.0f}, {hi:{sign}.0f}]"

    hours = result["safe_h" if kind == "label" else "calm_h"]
    lines = [f"Validation: {result['val_runs']} runs, {result['colliding_runs']} colliding, "
             f"{hours:.2f} h of safe driving; {FA_KINDS[kind]}.", "",
             "| variant | ≤ FA/h | warned ≥ 1.0 s % | Δ vs ref | warned ≥ 1.5 s % | Δ vs ref "
             "| warned % | median lead s | FA/h | AUROC | AUPRC | pAUC₁₀₋₃ | CPU s |",
             "|---|---:|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for name, row in result["rows"].items():
        f, rec = row["frame"], row["record"]
        for budget, b in row[f"proxy_{kind}"].items():
            p = b["point"]
            ref = result["rows"][row["reference"]][f"proxy_{kind}"][budget]["point"]
            d1, d15 = (p["warned_1s_pct"] - ref["warned_1s_pct"],
                       p["warned_1.5s_pct"] - ref["warned_1.5s_pct"])
            lines.append(
                f"| {name} | {budget} | {p['warned_1s_pct']:.0f} {ci(b, 'warned_1s_pct')} | "
                f"{d1:+.0f} {ci(b, 'warned_1s_pct', True)} | {p['warned_1.5s_pct']:.0f} "
                f"{ci(b, 'warned_1.5s_pct')} | {d15:+.0f} {ci(b, 'warned_1.5s_pct', True)} | "
                f"{p['warned_pct']:.0f} | {p['median_lead_s']:.2f} | {p['fa_per_h']:.2f} | "
                f"{f['auroc']:.2f} | {f['auprc']:.1f} | {f['pauc']:.1f} | {rec['cpu_s']:.0f} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("command", choices=("train", "rescore", "table"))
    ap.add_argument("--root", required=True)
    ap.add_argument("--variant", choices=sorted(VARIANTS))
    ap.add_argument("--variants", type=lambda s: s.split(","), default=["v3"])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--seeds", type=lambda s: [int(x) for x in s.split(",")], default=[0])
    ap.add_argument("--reference", default="v3")
    ap.add_argument("--split-seed", type=int, default=0)
    ap.add_argument("--train-frac", type=float, default=0.5)
    ap.add_argument("--val-frac", type=float, default=0.5)
    ap.add_argument("--test-batch", default="test-seed9103")
    ap.add_argument("--n-boot", type=int, default=1000)
    ap.add_argument("--boot-seed", type=int, default=0)
    ap.add_argument("--oracles", action="store_true",
                    help="add the ground truth's required deceleration as a trigger")
    ap.add_argument("--json", default=None)
    ap.add_argument("--md", default=None)
    args = ap.parse_args()
    if args.command == "train":
        if args.variant is None:
            ap.error("train needs --variant")
        train(args)
        return
    if args.command == "rescore":
        rescore(args)
        return
    result = table(args)
    text = markdown(result)
    print(text)
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1), encoding="utf-8")
    if args.md:
        Path(args.md).write_text(text + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
