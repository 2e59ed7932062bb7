"""Baseline runtime monitors behind the Monitor protocol: TTC and RSS rules, the AEM autoencoder,
and the context-only control (clock, ego speed and position).

`evoeye.evaluation.monitors.BASELINES` builds them by name; AEM (torch) and the control
(scikit-learn) are imported on use.
"""

from evoeye.baselines.rss import RSSMonitor, RssParams
from evoeye.baselines.ttc import TTCMonitor, min_ttc_s, ttc_risk

__all__ = ["RSSMonitor", "RssParams", "TTCMonitor", "min_ttc_s", "ttc_risk"]
