"""Baseline runtime monitors behind the Monitor protocol: TTC and RSS rules, the AEM autoencoder.

`evoeye.evaluation.monitors.BASELINES` builds them by name; AEM (torch) is imported on use.
"""

from evoeye.baselines.rss import RSSMonitor, RssParams
from evoeye.baselines.ttc import TTCMonitor, min_ttc_s, ttc_risk

__all__ = ["RSSMonitor", "RssParams", "TTCMonitor", "min_ttc_s", "ttc_risk"]
