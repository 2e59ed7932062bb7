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
from evoeye.ads.profiles import ADS_PROFILES, DEFAULT_PROFILE, ads_profile, check_profile
from evoeye.ads.stack import ADS

__all__ = [
    "ADS",
    "ADS_PROFILES",
    "DEFAULT_PROFILE",
    "ADSConfig",
    "ControlConfig",
    "LocalizationConfig",
    "PlanningConfig",
    "PredictionConfig",
    "SensorConfig",
    "TrackerConfig",
    "ads_profile",
    "check_profile",
]
