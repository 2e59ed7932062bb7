"""The modular ADS under monitoring: perception → prediction → planning → control."""

from evoeye.ads.config import (
    ADSConfig,
    ControlConfig,
    LocalizationConfig,
    PlanningConfig,
    PredictionConfig,
    SensorConfig,
    TrackerConfig,
)
from evoeye.ads.stack import ADS

__all__ = [
    "ADS",
    "ADSConfig",
    "ControlConfig",
    "LocalizationConfig",
    "PlanningConfig",
    "PredictionConfig",
    "SensorConfig",
    "TrackerConfig",
]
