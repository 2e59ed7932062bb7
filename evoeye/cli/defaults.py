"""Defaults shown in `--help`, kept here so that help never imports the heavy modules they come
from; tests/cli/test_defaults.py checks each against its source."""

# evoeye.ads.profiles.ADS_PROFILES
ADS_PROFILE_NAMES = ("default", "cautious", "firm-yield", "defensive")
WORLD_NAMES = ("default", "follower")  # evoeye.sim.worlds.WORLD_NAMES
DEFAULT_LOCKSTEP = 64  # evoeye.sim.lockstep.DEFAULT_BATCH
SPLIT_SEED, TRAIN_FRAC, VAL_FRAC = 0, 0.5, 0.125  # evoeye.store.SplitSpec()
# evoeye.monitor.recipes
RECIPE_NAMES, COMMAND_RECIPE = ("v1", "v2", "v3", "lookahead-v1"), "lookahead-v1"
STRATEGY_NAMES = ("evoeye", "no-feedback", "no-density", "uniform", "avfuzzer", "sobol",
                  "boundary", "disagreement", "evoeye-knn", "evoeye-forest", "ce-is",
                  "subset", "subset-deep",
                  "subset-spread")  # evoeye.evolve.search.STRATEGIES
FAMILY_NAMES = ("fusion", "aem")  # evoeye.monitor.families.evolvable_families()
METHOD_NAMES = (*STRATEGY_NAMES, "aem-evo")  # evoeye.evolve.campaign.experiment.methods()
CONTEXT_LEN = 5  # evoeye.store.windows.DEFAULT_CONTEXT_LEN
HORIZON_S = 3.0  # evoeye.store.windows.DEFAULT_HORIZON_S
TARGET_FPRS = (0.05, 0.01)  # evoeye.monitor.protocol.TARGET_FPRS
WARNING_K = 3  # evoeye.monitor.protocol.WARNING_K
RUNS_PER_PART = 32  # evoeye.store.ingest.DEFAULT_RUNS_PER_PART
MODULE_NAMES = ("perception", "prediction", "planning", "control")  # evoeye.monitor.inputs.MODULES
ABLATION_NAMES = ("perception", "perception+prediction", "perception+prediction+planning",
                  "all")  # evoeye.monitor.inputs.ABLATIONS
SWEEP_FPRS = (0.05, 0.02, 0.01, 0.005, 0.002, 0.001, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5,
              1e-5)  # evoeye.evaluation.supervision.triggers.SWEEP_FPRS
SWEEP_RECALLS = (0.2, 0.1, 0.05)  # evoeye.evaluation.supervision.triggers.RECALLS
SUPERVISE_BASELINES = ("ttc", "ttc-2d", "rss", "aem",
                       "context-only")  # evoeye.evaluation.supervision.triggers
SUPERVISE_BUDGETS = (0.5, 1.0, 2.0)  # evoeye.evaluation.supervision.summary.BUDGETS_PER_H
ORACLE_LEADS_S = (0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.5,
                  3.0)  # evoeye.evaluation.supervision.triggers.ORACLE_LEADS_S
LOG_POLICIES = ("none", "collided", "all")  # evoeye.evaluation.supervision.settings.LOG_POLICIES
FALLBACKS = {  # {name: FallbackConfig.to_dict()} of evoeye.sim.supervisor.FALLBACKS
    "production": {"decel_mps2": 9.0, "jerk_mps3": 30.0, "onset_s": 0.1, "hold_s": 1.0,
                   "standstill_mps": 0.1},
    "comfort": {"decel_mps2": 6.0, "jerk_mps3": 10.0, "onset_s": 0.1, "hold_s": 1.0,
                "standstill_mps": 0.1}}
DEFAULT_FALLBACK = "production"  # evoeye.sim.supervisor.DEFAULT_FALLBACK
