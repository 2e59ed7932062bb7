"""`evoeye results`: every table of docs/results, with its CIs and p-values, in one command."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from evoeye.cli.app import app
from evoeye.cli.choices import scenario_check, scenario_help
from evoeye.cli.output import StepBar
from evoeye.paths import DataRoot
from evoeye.results.config import (
    PAPER_INITIAL_RUNS,
    PARTS,
    RECIPES,
    ResultsConfig,
    parse_initial_runs,
)
from evoeye.results.efficiency.config import (
    MAX_MEMBERS,
    MODES,
    ORACLE_MIN_CANDIDATES,
    ORACLE_STEPS,
    REFERENCE,
    UPDATES,
    EfficiencyConfig,
)
from evoeye.results.rare.config import USABLE, LearnConfig, RareConfig

D = ResultsConfig()  # the defaults --help shows (config.py imports nothing heavy)
E = EfficiencyConfig()
R = RareConfig()
L = LearnConfig()


def _csv(text: str) -> tuple[str, ...]:
    return tuple(n.strip() for n in text.split(",") if n.strip() and n.strip() != "none")


def study_scenarios(scenario: list[str] | None, initial_runs: list[str] | None
                    ) -> tuple[str, ...]:
    """--scenario as given; without it every registered scenario, but the paper's alone for
    `--initial-runs paper` (the paper's data sizes exist for its scenarios only)."""
    if scenario:
        return tuple(scenario)
    return tuple(PAPER_INITIAL_RUNS) if initial_runs == ["paper"] else tuple(D.scenarios)


def with_reference(given: list[str] | None, default: tuple[str, ...]) -> tuple[str, ...]:
    """The strategies given, Uniform (the reference) first and always; else the default."""
    return tuple(dict.fromkeys((REFERENCE, *given))) if given else default


@app.command("results")
def results_command(
    root: Annotated[Path | None, typer.Option(
        "--root", help="Data root (default: $EVOEYE_HOME or ./evoeye-data).")] = None,
    scenario: Annotated[list[str] | None, typer.Option(
        "--scenario", callback=scenario_check(),
        help=scenario_help("Logical scenario (repeatable; default: every one)."))] = None,
    part: Annotated[list[str] | None, typer.Option(
        "--part", help=f"Run only these parts (repeatable): {', '.join(PARTS)}.")] = None,
    training_seeds: Annotated[int, typer.Option(
        min=2, help="Training seeds 0 … N−1 (RQ1, the ablation; the first k are RQ2's "
                    "re-seeded G_0s).")] =
        len(D.training_seeds),
    campaign_seeds: Annotated[int, typer.Option(
        min=2, help="Campaign seeds 0 … N−1, paired across the RQ2 methods.")] =
        len(D.campaign_seeds),
    final_seeds: Annotated[int, typer.Option(
        min=1, help="k: a campaign's final monitor is judged by the mean over k training "
                    "seeds of its last update.")] = D.final_seeds,
    final: Annotated[str, typer.Option(
        help="The k final monitors: 'update' (the campaign's last update again with k seeds: "
             "what a user of the method deploys) or 'retrain' (G_0's recipe trained from "
             "scratch on the campaign's D_R with G_0's k seeds: what the data it acquired is "
             "worth, whatever the update rule).")] = D.final,
    initial_runs: Annotated[list[str] | None, typer.Option(
        help="Simulate (or resume) this many initial runs per scenario, batch "
             "uniform-seed<sim-seed> (0: use the warehouse's): N for every scenario, "
             "SCENARIO=N for one, or 'paper' for the paper's "
             f"({', '.join(f'{n} on {s}' for s, n in PAPER_INITIAL_RUNS.items())}; alone and "
             "without --scenario, the study runs on those scenarios); repeatable.  "
             "[default: 0]")] = None,
    sim_seed: Annotated[int, typer.Option(min=0, help="Seed of the initial runs.")] =
        D.sim_seed,
    rq1_runs: Annotated[int, typer.Option(
        min=0, help="RQ1 and the monitor ablation train on at least this many initial runs per "
                    "scenario: if --initial-runs is fewer (and not 0), on their own (same seed, "
                    "same Test Set) under <root>/results/rq1-data; RQ2 keeps --initial-runs.")
    ] = D.rq1_runs,
    test_runs: Annotated[int, typer.Option(
        min=0, help="Simulate (or resume) this many runs per scenario as the held-out Test Set "
                    "batch (0: none, or the --test-batch already there).")] = D.test_runs,
    test_seed: Annotated[int, typer.Option(min=0, help="Seed of the Test Set batch.")] =
        D.test_seed,
    test_batch: Annotated[str | None, typer.Option(
        help="The Test Set batch's name (default test-seed<test-seed>).")] = None,
    split_seed: Annotated[int, typer.Option(min=0, help="Seed of the train/val split.")] =
        D.split_seed,
    train_frac: Annotated[float | None, typer.Option(
        help="Train share of the initial runs (default 0.8 with a Test Set batch, else 0.5).")
    ] = None,
    val_frac: Annotated[float | None, typer.Option(
        help="Validation share (default 0.2 with a Test Set batch, else 0.125).")] = None,
    baselines: Annotated[str, typer.Option(help="Comma-separated RQ1 baselines.")] =
        ",".join(D.baselines),
    context_len: Annotated[list[int] | None, typer.Option(
        "--context-len", help="Context lengths of the ablation (repeatable; default 1 3 5 7).")
    ] = None,
    inputs: Annotated[list[str] | None, typer.Option(
        "--inputs", help="Module inputs of the ablation (repeatable; default all four sets).")
    ] = None,
    method: Annotated[list[str] | None, typer.Option(
        "--method", help="RQ2 methods (repeatable; default the RQ2 ones and the ablations).")
    ] = None,
    budget_s: Annotated[float | None, typer.Option(
        min=0.0, help="Simulated seconds per campaign (default: the initial training data's).")
    ] = None,
    n_round: Annotated[int, typer.Option(min=1, help="Runs per round (N_round).")] = D.n_round,
    update: Annotated[str, typer.Option(help="Monitor update: finetune or retrain.")] =
        D.update,
    feedback: Annotated[str, typer.Option(help="Feedback: raw or prior-corrected.")] =
        D.feedback,
    epochs: Annotated[int | None, typer.Option(
        min=1, help="Epochs of every training (default: each trainer's).")] = None,
    patience: Annotated[int | None, typer.Option(min=1, help="Early-stopping patience.")] =
        None,
    regime: Annotated[list[str] | None, typer.Option(
        "--regime", help="Sample-efficiency study (--part efficiency): a regime, SCENARIO or "
                         "SCENARIO:ADS_PROFILE (repeatable; default "
                         f"{', '.join(E.regimes)}).")] = None,
    strategy: Annotated[list[str] | None, typer.Option(
        "--strategy", help="Sample-efficiency study: the strategies whose curves it draws, "
                           "beside Uniform's, the reference (repeatable; default "
                           f"{', '.join(E.strategies)}).")] = None,
    mode: Annotated[str, typer.Option(
        help=f"Sample-efficiency study: {' or '.join(MODES)} (pick from the pre-simulated "
             "pool, or simulate what each strategy proposes).")] = E.mode,
    study_seeds: Annotated[int, typer.Option(
        min=2, help="Sample-efficiency study: seeds, paired across strategies.")] =
        len(E.seeds),
    first_study_seed: Annotated[int, typer.Option(
        min=0, help="Sample-efficiency study: its first seed (seeds K … K+N−1).")] = 0,
    oracle: Annotated[bool, typer.Option(
        help="Sample-efficiency study: draw the greedy oracle's curves (a lower bound on what "
             "choosing runs can gain) and its two controls' (pool mode).")] = E.oracle,
    oracle_candidates: Annotated[int, typer.Option(
        min=ORACLE_MIN_CANDIDATES,
        help="Sample-efficiency study: increments the oracle tries per step (its "
             "best-of-k-seeds control: training seeds per checkpoint).")] =
        E.oracle_candidates,
    oracle_step: Annotated[str, typer.Option(
        help=f"Sample-efficiency study: the oracle chooses once per "
             f"{' or per '.join(ORACLE_STEPS)} (a round: the study's {E.n_round} runs; more "
             "steps adapt more, at more trainings).")] =
        E.oracle_step,
    study_update: Annotated[str, typer.Option(
        help=f"Sample-efficiency study: how the per-round monitor the strategies' feedback "
             f"comes from is updated, {' or '.join(UPDATES)} (fine-tuned, or trained again "
             "from scratch every round).")] = E.update,
    pool_runs: Annotated[int, typer.Option(
        min=1, help="Sample-efficiency study: uniform runs per regime to pick from.")] =
        E.pool_runs,
    members: Annotated[int, typer.Option(
        min=1, max=MAX_MEMBERS,
        help="Sample-efficiency study: each checkpoint's monitor is an ensemble of this many "
             "members trained from scratch (1: one monitor), scored by their mean risk.")] =
        E.members,
    val_collisions: Annotated[int, typer.Option(
        min=0, help="Sample-efficiency study: the validation set holds at least this many "
                    "colliding runs (further runs of its seed stream; 0: the uniform batch "
                    "alone).")] = E.val_collisions,
    data_seed: Annotated[int | None, typer.Option(
        min=0, help="Seed of every run the sample-efficiency study (its pool, Test, validation, "
                    "oracle and boundary sets) and the rare-failure protocol simulate: a fresh "
                    "one for a confirmation no screening drew from (default: each its own, "
                    f"{E.data_seed} and {R.data_seed}).")] = None,
    rare_regime: Annotated[list[str] | None, typer.Option(
        "--rare-regime", help="Rare-failure protocol (--part rare): a regime, "
                              "SCENARIO:ADS_PROFILE (repeatable; default "
                              f"{', '.join(R.regimes)}).")] = None,
    rare_strategy: Annotated[list[str] | None, typer.Option(
        "--rare-strategy", help="Rare-failure protocol: the strategies that simulate their own "
                                f"runs beside Uniform's, the reference, from {', '.join(USABLE)} "
                                f"(repeatable; default {', '.join(R.strategies)}).")] = None,
    rare_seeds: Annotated[int, typer.Option(
        min=2, help="Rare-failure protocol: seeds, paired across strategies.")] = len(R.seeds),
    first_rare_seed: Annotated[int, typer.Option(
        min=0, help="Rare-failure protocol: its first seed (seeds K … K+N−1).")] = 0,
    rare_runs: Annotated[int, typer.Option(
        min=1, help="Rare-failure protocol: runs simulated per seed and strategy.")] = R.runs,
    rare_batch: Annotated[int, typer.Option(
        min=1, help="Rare-failure protocol: runs between two adaptations of a strategy "
                    "(--rare-runs must be whole batches).")] = R.batch,
    rare_explain: Annotated[bool, typer.Option(
        help="Rare-failure protocol: attribute every collision found to a module by "
             "`evoeye explain`'s counterfactuals (4 more simulations per collision).")] =
        R.explain,
    rare_learn: Annotated[bool, typer.Option(
        help="Rare-failure protocol: also train a monitor from scratch on each curve's first "
             f"{', '.join(map(str, L.budgets))} runs (importance-weighted by their p/q) and "
             "judge it on a uniform Test Set of its own (the learning side).")] = False,
    rare_test_runs: Annotated[int, typer.Option(
        min=1, help="Rare-failure protocol, learning side: uniform Test Set runs per regime "
                    "(enough to hold ≥ 50 failures).")] = L.test_runs,
    rare_test_max_runs: Annotated[int, typer.Option(
        min=0, help="Rare-failure protocol, learning side: where the Test Set's runs hold "
                    "fewer than 50 failures, draw its stream on to this many runs at most, "
                    "logging only the collisions, and weight the set back (0: no more runs).")
    ] = L.test_max_runs,
    rare_members: Annotated[int, typer.Option(
        min=1, max=8, help="Rare-failure protocol, learning side: from-scratch members of "
                           "each monitor.")] = L.members,
    rare_learn_control: Annotated[list[str] | None, typer.Option(
        "--rare-learn-control", help="Rare-failure protocol, learning side: a weighted "
        "strategy (ce-is) whose runs also train unweighted, beside, as the control for what "
        "the weights add (repeatable).")] = None,
    rare_learn_strategy: Annotated[list[str] | None, typer.Option(
        "--rare-learn-strategy", help="Rare-failure protocol, learning side: learn only from "
        "these strategies' curves, beside Uniform's (repeatable; default every strategy's).")
    ] = None,
    recipe: Annotated[str, typer.Option(
        help=f"Training recipe of every monitor trained from scratch, one of "
             f"{', '.join(RECIPES)} (campaign updates keep theirs).")] = D.recipe,
    workers: Annotated[int, typer.Option(
        min=1, help="Processes simulating the data, then running campaigns side by side.")
    ] = D.workers,
    name: Annotated[str, typer.Option(help="Report folder under <root>/reports.")] =
        "results",
    docs: Annotated[Path | None, typer.Option(
        help="Also copy rq1.md, rq2.md, findings.md and results.json here (docs/results).")
    ] = None,
    readme: Annotated[Path | None, typer.Option(
        help="Also rewrite this README's findings section (between its markers).")] = None,
) -> None:
    """Regenerate RQ1, the monitor ablation, RQ2, the evolution ablations and AEM-Evo — and,
    with --part efficiency, the sample-efficiency study (learning curves of acquisition
    strategies against Uniform and a greedy oracle); with --part rare, the rare-failure
    protocol (failures found, failure-rate estimates and distinct mechanisms per simulated run,
    against Uniform's) — each comparison with its mean, 95 % CI and p; re-running reuses every
    finished unit."""
    from evoeye.results.efficiency.part import failed_units
    from evoeye.results.rare.part import failed_curves
    from evoeye.results.run import run_results, write_results

    fresh = {} if data_seed is None else {"data_seed": data_seed}
    try:
        runs = parse_initial_runs(initial_runs or [])
        config = ResultsConfig(
            scenarios=study_scenarios(scenario, initial_runs), parts=tuple(part or D.parts),
            training_seeds=tuple(range(training_seeds)),
            campaign_seeds=tuple(range(campaign_seeds)), final_seeds=final_seeds, final=final,
            initial_runs=runs, sim_seed=sim_seed, rq1_runs=rq1_runs,
            test_runs=test_runs,
            test_seed=test_seed, test_batch=test_batch, split_seed=split_seed,
            train_frac=train_frac, val_frac=val_frac, baselines=_csv(baselines),
            context_lens=tuple(context_len or D.context_lens),
            inputs=tuple(inputs or D.inputs), methods=tuple(method or D.methods),
            budget_s=budget_s, n_round=n_round, update=update, feedback=feedback,
            epochs=epochs, patience=patience, recipe=recipe, workers=workers,
            efficiency=EfficiencyConfig(
                regimes=tuple(regime or E.regimes),
                strategies=with_reference(strategy, E.strategies),
                mode=mode, update=study_update,
                seeds=tuple(range(first_study_seed, first_study_seed + study_seeds)),
                oracle=oracle, oracle_candidates=oracle_candidates, oracle_step=oracle_step,
                pool_runs=pool_runs, recipe=recipe, epochs=epochs,
                patience=patience, members=members, val_collisions=val_collisions,
                **fresh
            ).changed(),
            rare=RareConfig(
                regimes=tuple(rare_regime or R.regimes),
                strategies=with_reference(rare_strategy, R.strategies),
                seeds=tuple(range(first_rare_seed, first_rare_seed + rare_seeds)),
                runs=rare_runs, batch=rare_batch, explain=rare_explain,
                learn={"test_runs": rare_test_runs, "members": rare_members,
                       "recipe": recipe, "test_max_runs": rare_test_max_runs,
                       "controls": tuple(rare_learn_control or ()),
                       "strategies": tuple(rare_learn_strategy or ())}
                if rare_learn else None, **fresh).changed())
        config.check_names()
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None
    simulates = (any(map(config.runs_of, config.scenarios)) or test_runs
                 or {"efficiency", "rare"} & set(config.parts))
    data = DataRoot.resolve(root) if simulates else DataRoot.existing(root)
    with StepBar("results") as bar:
        run = run_results(data, config, progress=bar)
    folder = write_results(data, run.results, name, docs=docs, readme=readme)
    typer.echo((folder / "findings.md").read_text(encoding="utf-8"))
    found, done = sum(run.found.values()), sum(run.computed.values())
    typer.echo(f"units: {found} found done, {done} done now ({run.computed or 'nothing new'})")
    typer.echo(f"report: {folder / 'results.html'} (tables: rq1.md, rq2.md, results.json)")
    failed = failed_units(run.results["efficiency"]) if "efficiency" in run.results else []
    failed += failed_curves(run.results["rare"]) if "rare" in run.results else []
    if failed:  # every other curve is in the report; the command still fails
        typer.echo(f"{len(failed)} curve(s) failed and are left out (re-run to retry them):",
                   err=True)
        for line in failed:
            typer.echo(f"  {line}", err=True)
        raise typer.Exit(1)
