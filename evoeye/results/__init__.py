"""The paper's results, regenerated with their uncertainty: `evoeye results`.

    ResultsConfig(...)                         what to run, at what size (config.py)
    run_results(root, config) -> ResultsRun     data, RQ1, ablation, RQ2; tables; findings
    write_results(root, results, name)          results.json, rq1.md, rq2.md, findings.md, HTML

A layer above `evoeye.evolve` (it runs campaigns through the experiment API) and
`evoeye.evaluation`. Imported on first use, so the command line can read `ResultsConfig`
without loading the rest.
"""

from evoeye.lazy import lazy_attributes

_LAZY = {
    "ResultsConfig": "evoeye.results.config",
    "ResultsRun": "evoeye.results.run",
    "run_results": "evoeye.results.run",
    "write_results": "evoeye.results.run",
}

__getattr__ = lazy_attributes(__name__, _LAZY)

__all__ = list(_LAZY)
