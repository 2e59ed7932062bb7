"""TTC: time to collision along the ego's corridor (`evoeye.baselines.ttc`)."""

from evoeye.evaluation.baselines import BaselineSpec


def _ttc():
    from evoeye.baselines.ttc import TTCMonitor

    return TTCMonitor()


BASELINE = BaselineSpec("ttc", "TTC", rule=_ttc, order=0)
