"""TTC-2D: the exact first contact of oriented boxes (`evoeye.baselines.ttc`)."""

from evoeye.evaluation.baselines import BaselineSpec


def _ttc_2d():
    from evoeye.baselines.ttc import TTC2DMonitor

    return TTC2DMonitor()


BASELINE = BaselineSpec("ttc-2d", "TTC-2D", rule=_ttc_2d, order=1)
