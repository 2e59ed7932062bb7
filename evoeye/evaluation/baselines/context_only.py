"""The context-only control: clock, ego speed and position, no module message (the
`context-only` monitor family); and where-when, the same without the ego's speed."""

from evoeye.evaluation.baselines import BaselineSpec

BASELINE = (BaselineSpec("context-only", "context-only", family="context-only", order=5),
            BaselineSpec("where-when", "where-when", family="where-when", order=6))
