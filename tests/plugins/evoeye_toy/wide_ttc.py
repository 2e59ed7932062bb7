"""A baseline in one file: TTC over a corridor 2 m wider on each side. Registered by the entry
point `[project.entry-points."evoeye.baselines"] wide-ttc = "evoeye_toy.wide_ttc:BASELINE"`."""

from evoeye.evaluation.baselines import BaselineSpec


def wide_ttc():
    from evoeye.baselines.ttc import TTCMonitor

    return TTCMonitor(name="toy-wide-ttc", corridor_margin_m=2.0)


BASELINE = BaselineSpec("toy-wide-ttc", "TTC (wide corridor)", rule=wide_ttc)
