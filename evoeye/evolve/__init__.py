"""Self-evolution, the pure core: feedback, density-aware mutation, acquisition strategies.

The loop (simulate, retrain every N_round records, refresh feedback, stop on the simulated-time
budget) lives with the flows; it drives a `Strategy` through `propose` / `tell` and resumes it
with `replay`.
"""

from evoeye.evolve.avfuzzer import AVFuzzer, AVFuzzerConfig, criticality
from evoeye.evolve.feedback import ScenarioFeedback, normalise_feedback, scenario_feedback
from evoeye.evolve.mutation import (
    DensityIndex,
    Mutation,
    density_aware_mutation,
    exploit_probability,
    regional_potential,
)
from evoeye.evolve.protocol import Proposal, Strategy, StrategyError
from evoeye.evolve.records import Records
from evoeye.evolve.strategies import STRATEGIES, DensityStrategy, UniformStrategy, make_strategy

__all__ = [
    "STRATEGIES",
    "AVFuzzer",
    "AVFuzzerConfig",
    "DensityIndex",
    "DensityStrategy",
    "Mutation",
    "Proposal",
    "Records",
    "ScenarioFeedback",
    "Strategy",
    "StrategyError",
    "UniformStrategy",
    "criticality",
    "density_aware_mutation",
    "exploit_probability",
    "make_strategy",
    "normalise_feedback",
    "regional_potential",
    "scenario_feedback",
]
