"""Is search worth it here? How well θ alone predicts a run's outcome and a monitor's error.

A strategy that chooses θ can only beat Uniform if what it steers by is predictable from θ
before the run is simulated. Per regime (logical scenario, ADS profile), on a batch of runs:

* cross-validated, how well a forest on normalised θ predicts a run's collision (AUROC), its
  signed safety margin (R², Spearman; the `boundary` strategy's target) and a monitor's error
  |ŷ − y| on runs that monitor did not train on (R², Spearman) — `metrics.py`;
* label noise: a sample of θ re-simulated with k new seeds, how often the outcome flips —
  `check.py`;
* a plain verdict, and the report as JSON and Markdown — `report.py`.
"""
