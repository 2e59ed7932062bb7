"""Baseline runtime monitors behind the Monitor protocol: TTC (corridor), TTC-2D (oriented boxes)
and RSS rules, the AEM autoencoder, and the context-only control (clock, ego speed and position).

`evoeye.evaluation.monitors.BASELINES` builds them by name. The trained ones (AEM, context-only)
are monitor families (`evoeye.baselines.families`, registered on import of this package); AEM
(torch) and the control (scikit-learn) are imported on use.
"""

from evoeye.baselines import families  # noqa: F401  (registers the aem and context-only families)
from evoeye.baselines.rss import CARLA_OTHER_VEHICLES, RSSMonitor, RssParams
from evoeye.baselines.ttc import TTC2DMonitor, TTCMonitor, min_ttc_2d_s, min_ttc_s, ttc_risk

__all__ = ["CARLA_OTHER_VEHICLES", "RSSMonitor", "RssParams", "TTC2DMonitor", "TTCMonitor",
           "min_ttc_2d_s", "min_ttc_s", "ttc_risk"]
