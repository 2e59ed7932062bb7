"""RSS (ad-rss's parameters), and rss-2s: CARLA's 2 s response time for the other vehicles, a
constructor argument of the same rule (`evoeye.baselines.rss`)."""

from evoeye.evaluation.baselines import BaselineSpec


def _rss():
    from evoeye.baselines.rss import RSSMonitor

    return RSSMonitor()


def _rss_2s():
    from evoeye.baselines.rss import CARLA_OTHER_VEHICLES, RSSMonitor

    return RSSMonitor(other=CARLA_OTHER_VEHICLES, name="rss-2s")


BASELINE = (BaselineSpec("rss", "RSS", rule=_rss, order=2),
            BaselineSpec("rss-2s", "RSS-2s", rule=_rss_2s, order=3))
