"""The search, pure: acquisition strategies over a logical scenario and their arithmetic.

No I/O and no monitor: a strategy proposes concrete scenarios (`propose(records)`), hears back
each one's fitness (`tell`), and reads the records' monitor-oriented feedback; the campaign
(`evoeye.evolve.campaign`) simulates, scores and stores. Here: the `Strategy` protocol and the
`STRATEGIES` registry (`registry.py`), pool mode (`pool.py`), density-aware mutation, the
feedback maths, AV-Fuzzer's GA operators, the surrogates (scikit-learn), and `criticality`,
the fitness every strategy's runs are scored by.
"""

from evoeye.evolve.search.avfuzzer import AVFuzzer, AVFuzzerConfig
from evoeye.evolve.search.feedback import (
    ScenarioFeedback,
    normalise_feedback,
    prior_corrected,
    scenario_feedback,
)
from evoeye.evolve.search.fitness import CRITICALITY_SCALE_M, criticality
from evoeye.evolve.search.mutation import (
    DensityIndex,
    Mutation,
    density_aware_mutation,
    exploit_probability,
    regional_potential,
)
from evoeye.evolve.search.pool import CandidatePool, PooledStrategy
from evoeye.evolve.search.protocol import Proposal, Strategy, StrategyError
from evoeye.evolve.search.records import Records
from evoeye.evolve.search.registry import (
    FEEDBACK_BLIND,
    GENERATIVE_ONLY,
    READS_DISAGREEMENT,
    STRATEGIES,
    make_strategy,
    strategy_options,
)
from evoeye.evolve.search.strategies import DensityStrategy, UniformStrategy

__all__ = [
    "CRITICALITY_SCALE_M",
    "FEEDBACK_BLIND",
    "GENERATIVE_ONLY",
    "STRATEGIES",
    "AVFuzzer",
    "AVFuzzerConfig",
    "CandidatePool",
    "DensityIndex",
    "DensityStrategy",
    "Mutation",
    "PooledStrategy",
    "Proposal",
    "READS_DISAGREEMENT",
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
    "prior_corrected",
    "regional_potential",
    "scenario_feedback",
    "strategy_options",
]
