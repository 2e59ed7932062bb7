"""The learning side of the rare-failure protocol: what a monitor learns from a strategy's runs.

The testing side (`runner.py`) asks what a strategy's runs find; this asks whether a monitor
trained on them predicts the regime's collisions better than one trained on Uniform's. Per
curve (a strategy's `runs` runs at one seed, as recorded), at each budget of `budgets` (the
curve's first n runs) a monitor is trained from scratch on those runs' windows and judged on
the regime's Test Set by its AUPRC; the curve's figure is the area under that curve over
log2(budget) (`efficiency.summary.area`), paired with Uniform's at the same seed.

* **The runs.** A curve's runs are simulated again from their recorded θ and run seed, in
  memory (the runner's seeds; the same bits), and each one's outcome is checked against the
  record: a run that does not reproduce is an error, not a silent change of data.
* **Importance weights.** Every monitor trains with its runs' p/q (`TrainParams.
  importance_weights`, `evoeye.monitor.importance`: self-normalised, clipped at √n): exact for
  `ce-is`'s runs, 1 for Uniform's (drawn from p). Subset simulation's runs carry no density;
  they train unweighted, so their shift towards failures is not corrected (the report says so).
* **No redraw.** A budget whose runs hold no window a monitor can learn a collision from gets
  no network: its monitor scores every frame alike (AUPRC = the Test Set's unsafe share, the
  no-skill figure) and is part of the result, as the issue asks of a curve that starts with no
  failure. A curve with no collision among its runs is not simulated again (every budget of
  it is no-skill; at ≈ 0.1 % most curves are): its outcomes are the recorded ones, unchecked.
* **The sets no strategy shaped.** The Test Set is `test_runs` uniform runs of their own seed
  (data_seed + 1), large enough to hold ≥ `min_test_failures` collisions where failures are
  ≈ 1 %. Where they are rarer, `test_max_runs` draws that stream on, outcome first, until it
  holds them, and the Test Set is the stream stratified by outcome and weighted back to it
  (`testset.py`: every colliding run, the batch's safe runs each standing for several). A
  regime whose Test Set holds fewer is reported with its count, and its check is not shown.
  Validation (early stopping and calibration) is `val_runs` uniform runs (data_seed + 2)
  and the unsafe windows of further runs of that stream until it holds `val_collisions`
  colliding runs (`efficiency.data.draw_collisions`): its negatives stay the uniform batch's.
* **Pairing.** The training seed of seed s at budget n is shared by every strategy
  (`efficiency.curves.training_seed`), so strategies differ only in their runs. With `members`
  > 1 a checkpoint's monitor is an ensemble of that many from-scratch members.

`strategies` limits the side to some strategies' curves (Uniform's always): learning costs a
simulation and three trainings per curve with a collision, and the other curves stay on the
testing side. Each learned curve is a ledger unit keyed by its curve, this config, the sets
and the software version: a killed run resumes with the curves it had not learned.
"""

from __future__ import annotations

import hashlib
import multiprocessing as mp
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from evoeye import __version__
from evoeye.batch import DEFAULT_LOCKSTEP, plan_uniform, run_batch
from evoeye.evaluation.stats import compare_paired, mean_ci
from evoeye.evolve.campaign.assess import metrics_dict
from evoeye.evolve.search.cross_entropy import effective_size
from evoeye.lifeline import die_with_parent
from evoeye.monitor.calibration import calibrate
from evoeye.monitor.lookahead import training_windows
from evoeye.monitor.recipes import recipe_params
from evoeye.monitor.threads import intra_op_threads
from evoeye.paths import DataRoot
from evoeye.results.efficiency.config import parse_regime
from evoeye.results.efficiency.curves import training_seed
from evoeye.results.efficiency.data import draw_collisions, kept_collisions
from evoeye.results.efficiency.learner import Learner
from evoeye.results.efficiency.power import detectable
from evoeye.results.efficiency.sets import concat_windows, with_unsafe_windows
from evoeye.results.efficiency.summary import area
from evoeye.results.ledger import Ledger
from evoeye.results.rare.config import UNWEIGHTED, LearnConfig, RareConfig
from evoeye.results.rare.runner import run_seed
from evoeye.results.rare.summary import weights as curve_weights
from evoeye.results.rare.testset import TestDraw, draw_test_failures
from evoeye.sim.lockstep import DEFAULT_BATCH, run_indexed
from evoeye.sim.runner import run_spec
from evoeye.store import Warehouse, ingest
from evoeye.store.log_windows import episode_run
from evoeye.store.windows import Windows, load_windows

Say = Callable[[str], None]
KIND = "rare-learn"
TEST_OFFSET, VAL_OFFSET = 1, 2  # the sets' seeds: data_seed + these
_CONTEXT: _Context | None = None  # what a forked worker inherits


def learn_root(root: DataRoot, regime: str) -> DataRoot:
    """The data root of a regime's Test and validation sets under the protocol's root."""
    scenario, profile = parse_regime(regime)
    return DataRoot(root.path / "rare" / f"{scenario}--{profile}")


def set_batch(name: str, data_seed: int) -> tuple[str, int]:
    """(batch, seed) of the Test ("test") or validation ("val") set."""
    seed = data_seed + (TEST_OFFSET if name == "test" else VAL_OFFSET)
    return f"{name}-seed{seed}", seed


def prepare_sets(root: DataRoot, regime: str, learn: LearnConfig, data_seed: int, *,
                 workers: int = 1, say: Say | None = None) -> tuple[DataRoot, TestDraw | None]:
    """Simulate (or resume) and ingest a regime's Test and validation sets; their data root,
    and the Test stream's draw past its batch (`testset.py`; None without `test_max_runs`)."""
    say = say or (lambda msg: None)
    scenario, profile = parse_regime(regime)
    data = learn_root(root, regime)
    simulated = {}
    for name, n in (("test", learn.test_runs), ("val", learn.val_runs)):
        batch, seed = set_batch(name, data_seed)
        say(f"{regime}: {name} set, {n} runs (seed {seed})")
        simulated[name] = run_batch(plan_uniform(scenario, n, seed, batch=batch, ads=profile),
                                    data, workers=workers, lockstep=DEFAULT_LOCKSTEP)
    draw = None
    if learn.test_max_runs:
        draw = draw_test_failures(data, regime, set_batch("test", data_seed)[1],
                                  simulated["test"], learn.min_test_failures,
                                  learn.test_max_runs, workers=workers, say=say)
    if learn.val_collisions:
        batch, seed = set_batch("val", data_seed)
        draw_collisions(data, regime, seed, learn.val_runs, learn.val_collisions, batch,
                        workers=workers, say=say)
    say(f"{regime}: ingesting")
    ingest(data, workers=workers)
    return data, draw


def load_sets(data: DataRoot, learn: LearnConfig, data_seed: int,
              draw: TestDraw | None = None) -> tuple[dict[str, Windows], np.ndarray | None]:
    """{"test", "val"} windows of a regime's sets (validation with its further collisions'
    unsafe windows; the Test Set with the further colliding runs of its stream, `draw`), and
    the Test Set's per-window weights (None: unweighted)."""
    def windows(runs):
        return load_windows(data, runs, context_len=learn.context_len, horizon_s=learn.horizon_s)

    def of_batch(name: str, safe: bool = False):
        return (f"SELECT scenario_id FROM scenarios WHERE batch = "
                f"'{set_batch(name, data_seed)[0]}' AND status = 'ok'"
                + (" AND NOT collided" if safe else ""))

    out = {name: windows(of_batch(name)) for name in ("test", "val")}
    _, seed = set_batch("val", data_seed)
    if extra := kept_collisions(data, seed, learn.val_runs, learn.val_collisions):
        out["val"] = with_unsafe_windows(out["val"], windows(extra))
    if draw is None:
        return out, None
    if draw.further:
        out["test"] = concat_windows([out["test"], windows(list(draw.further))])
    safe = Warehouse(data).sql(of_batch("test", safe=True)).column("scenario_id").to_pylist()
    stands_for = np.isin(np.asarray(out["test"].scenario_id).astype(str), safe)
    return out, np.where(stands_for, draw.safe_weight, 1.0)


def set_figures(windows: Windows) -> dict:
    """Runs, colliding runs, windows and unsafe windows of a set."""
    ids = np.asarray(windows.scenario_id).astype(str)
    hit = np.unique(ids[windows.label == 1])
    return {"runs": int(len(np.unique(ids))), "failures": int(len(hit)),
            "windows": int(len(windows)), "unsafe": int(windows.label.sum())}


def fingerprint(sets: dict[str, Windows]) -> str:
    h = hashlib.sha256()
    for name in sorted(sets):
        h.update(name.encode())
        h.update("\n".join(sorted(set(np.asarray(sets[name].scenario_id).astype(str))))
                 .encode())
    return h.hexdigest()[:20]


@dataclass
class _Context:
    regime: str
    learn: LearnConfig
    learner: Learner
    set_print: str  # the sets' fingerprint: a learned curve is keyed by it
    ledger: Ledger
    config: RareConfig  # the protocol's: its curves' keys and run seeds


def curve_windows(regime: str, curve: dict, seed_of: Callable[[int], int], n: int,
                  learn: LearnConfig) -> tuple[list, list[str]]:
    """(windows per run, run ids) of a curve's first n runs, simulated again in memory from
    their recorded θ and run seed (stepped together by the lockstep engine: `run_episode`'s
    runs, bit for bit); RuntimeError where a run's outcome differs from its record."""
    scenario, profile = parse_regime(regime)
    specs = [run_spec(scenario, np.asarray(curve["x"][k], float), seed_of(k), ads=profile)
             for k in range(n)]
    out: list = [None] * n
    for k, ep in run_indexed(specs, size=DEFAULT_BATCH):
        collided = bool(ep.outcome.collided) and ep.outcome.status == "ok"
        if collided != bool(curve["runs"][k]["collided"]):
            raise RuntimeError(f"run {k} ({ep.spec.scenario_id}) did not reproduce its "
                               f"recorded outcome (collided {curve['runs'][k]['collided']}, "
                               f"now {collided}): the simulator changed since the curve was run")
        run = episode_run(ep, Path("memory") / ep.spec.scenario_id, learn.context_len,
                          learn.horizon_s)
        out[k] = run.windows if run.ok else None
    return out, [spec.scenario_id for spec in specs]


def learnable(train: Windows | None, params) -> bool:
    """Whether a monitor can learn from these windows: both classes among those its recipe
    trains on (`training_windows`)."""
    if train is None or not len(train):
        return False
    kept = training_windows(train, params.min_lead_s, params.near_misses).label
    return bool(kept.any()) and not bool(kept.all())


def no_skill(learner: Learner) -> dict:
    """The judging figures of a monitor that scores every frame alike (module doc)."""
    thresholds = calibrate(np.zeros(len(learner.val)), learner.val.label)
    return {name: metrics_dict(np.zeros(len(w)), w.label, thresholds,
                               learner.judging_weights.get(name))
            for name, w in learner.judging.items()}


def learn_curve(ctx: _Context, strategy: str, seed: int, curve: dict,
                weighted: bool = True) -> dict:
    """One curve's figures: per budget the Test Set metrics of its monitor, the collisions it
    trained on, its runs' effective number under their weights, and whether it is no-skill;
    with `weighted` False every run weighs 1 (the control for what the weights add)."""
    learn, last = ctx.learn, ctx.learn.budgets[-1]
    if any(r["collided"] for r in curve["runs"][:last]):
        runs, ids = curve_windows(ctx.regime, curve,
                                  lambda k: run_seed(ctx.config, ctx.regime, strategy, seed, k),
                                  last, learn)
    else:  # nothing to learn at any budget: every monitor is no-skill, no run is needed again
        runs, ids = [None] * last, [""] * last
    ratio = curve_weights(curve)[:last] if weighted else np.ones(last)
    out = {}
    with intra_op_threads():
        for n in learn.budgets:
            have = [w for w in runs[:n] if w is not None and len(w)]
            train = concat_windows(have) if have else None
            w = {ids[k]: float(ratio[k]) for k in range(n)}
            row = {"collisions": int(sum(r["collided"] for r in curve["runs"][:n])),
                   "effective_runs": effective_size(ratio[:n]),
                   "max_weight": float(ratio[:n].max())}
            if learnable(train, ctx.learner.params):
                monitor = ctx.learner.checkpoint(train, training_seed(seed, n), w)
                row.update(ctx.learner.judge(monitor), no_skill=False)
            else:
                row.update(no_skill(ctx.learner), no_skill=True)
            out[str(n)] = row
    return {"budgets": out}


def _unit(job: tuple[str, int, dict]) -> tuple[str, int, dict, bool]:
    name, seed, curve = job  # name: a strategy, or its control (`UNWEIGHTED`)
    strategy = name.removesuffix(UNWEIGHTED)
    weighted = name == strategy
    ctx = _CONTEXT
    assert ctx is not None, "a worker needs the regime's context"
    key = {"curve": ctx.config.unit(ctx.regime, strategy, seed), "learn": ctx.learn.curve_key(),
           "sets": ctx.set_print, "software_version": __version__,
           **({} if weighted else {"weighted": False})}
    before = sum(ctx.ledger.computed.values())
    try:
        learned = ctx.ledger.remember(
            KIND, key, lambda: learn_curve(ctx, strategy, seed, curve, weighted))
    except Exception as exc:  # noqa: BLE001 — one curve's failure must not stop the others
        return name, seed, {"error": f"{type(exc).__name__}: {exc}"}, False
    return name, seed, learned, sum(ctx.ledger.computed.values()) > before


def learn_regime(root: DataRoot, regime: str, curves: dict[str, dict[str, dict]],
                 config: RareConfig, *, workers: int = 1, say: Say | None = None) -> dict:
    """The learning side of one regime (module doc): {"config", "sets", "curves": {strategy:
    {seed: learned}}, "failed", "computed"}. `curves`: the regime's recorded curves; `config`:
    the protocol's RareConfig, with its learning side (`config.learning`)."""
    global _CONTEXT
    learn = config.learning
    if learn is None:
        raise ValueError("the protocol's config has no learning side (RareConfig.learn)")
    say = say or (lambda msg: None)
    data, draw = prepare_sets(root, regime, learn, config.data_seed, workers=workers, say=say)
    sets, test_weight = load_sets(data, learn, config.data_seed, draw)
    params = replace(recipe_params(learn.recipe), importance_weights=True)
    learner = Learner(sets["val"], {"test": sets["test"]}, params, learn.members,
                      {} if test_weight is None else {"test": test_weight})
    _CONTEXT = _Context(regime, learn, learner, fingerprint(sets), Ledger(root), config)
    jobs = [(name, int(seed), curve) for seed in sorted({int(s) for c in curves.values()
                                                         for s in c})
            for strategy, by_seed in curves.items()
            if learn.learns(strategy) and (curve := by_seed.get(str(seed)))
            for name in (strategy, *([strategy + UNWEIGHTED] if strategy in learn.controls
                                     else []))]
    learned: dict[str, dict[str, dict]] = {}
    failed, computed = [], 0

    def keep(strategy: str, seed: int, row: dict, now: bool) -> None:
        nonlocal computed
        computed += now
        if "error" in row:
            failed.append({"strategy": strategy, "seed": seed, "error": row["error"]})
            say(f"{regime}: learning from {strategy} seed {seed} FAILED: {row['error']}")
            return
        learned.setdefault(strategy, {})[str(seed)] = row
        last = row["budgets"][str(learn.budgets[-1])]
        say(f"{regime}: learned from {strategy} seed {seed}: Test AUPRC "
            f"{last['test']['auprc']:.3f} at {learn.budgets[-1]} runs")

    try:
        if workers == 1:
            for done in map(_unit, jobs):
                keep(*done)
        else:
            with ProcessPoolExecutor(workers, mp_context=mp.get_context("fork"),
                                     initializer=die_with_parent,
                                     initargs=(os.getpid(),)) as pool:
                for done in pool.map(_unit, jobs):
                    keep(*done)
    finally:
        _CONTEXT = None
    figures = {name: set_figures(w) for name, w in sets.items()}
    if draw is not None:
        figures["test"].update(draw.to_dict())
    return {"config": learn.to_dict(), "sets": figures,
            "curves": learned, "failed": failed, "computed": computed}


def summarise_learning(learned: dict, reference: str = "uniform") -> dict:
    """`learn_regime`'s sets and config, and per strategy: the mean Test AUPRC (points) at
    each budget, the area under the curve (mean with its t interval), the mean collisions
    trained on, the no-skill share; beside Uniform, the paired difference of the areas
    (`compare_paired`) and what the seeds could detect (`efficiency.power.detectable`)."""
    budgets = [int(b) for b in learned["config"]["budgets"]]
    curves = learned["curves"]
    seeds = sorted({int(s) for c in curves.values() for s in c})

    def table(name: str, key: Callable[[dict], float]) -> np.ndarray:
        rows = curves.get(name, {})
        return np.array([[key(rows[str(s)]["budgets"][str(b)]) if str(s) in rows else np.nan
                          for b in budgets] for s in seeds], float)

    def auprc(row: dict) -> float:
        value = row["test"]["auprc"]
        return np.nan if value is None else 100.0 * value

    out = {"budgets": budgets, "seeds": len(seeds), "strategies": {},
           "sets": learned["sets"], "config": learned["config"]}
    areas = {name: area(table(name, auprc), budgets) for name in curves}
    for name in curves:
        values = table(name, auprc)
        row = {"seeds": int(np.isfinite(areas[name]).sum()),
               "auprc": [mean_ci(values[:, j]).to_dict() for j in range(len(budgets))],
               "area": mean_ci(areas[name]).to_dict(),
               "collisions": np.nanmean(table(name, lambda r: r["collisions"]), 0).tolist(),
               "no_skill": np.nanmean(table(name, lambda r: float(r["no_skill"])), 0).tolist(),
               "effective_runs": np.nanmean(table(name, lambda r: r["effective_runs"]),
                                            0).tolist()}
        if name != reference and reference in areas:
            row["vs_reference"] = {
                "area": compare_paired(areas[name], areas[reference]).to_dict(),
                "final": compare_paired(values[:, -1], table(reference, auprc)[:, -1]).to_dict(),
                "detectable": detectable(areas[name], areas[reference])}
        if (base := name.removesuffix(UNWEIGHTED)) != name and base in areas:
            row["weights_add"] = {  # the weighted curves' area − this control's, per seed
                "area": compare_paired(areas[base], areas[name]).to_dict(),
                "detectable": detectable(areas[base], areas[name])}
        out["strategies"][name] = row
    return out
