"""Self-evolution, in two halves that meet only through the `Strategy` protocol and `Records`.

* `evoeye.evolve.search` — the pure search: acquisition strategies (BlindSpotEvolver and its
  ablations, Uniform, AV-Fuzzer), density-aware mutation, the feedback maths and `criticality`.
  numpy and the logical scenario space only: no I/O, no monitor, no warehouse.
* `evoeye.evolve.campaign` — the campaign with its I/O: Algorithm 1 as a resumable loop over a
  data root (simulate, log, ingest, train the monitor, store feedback and rounds), its
  configuration, the Test / Hard Set assessment, and the RQ2 experiment and report. The flows
  (`flows/evolve.py`, `flows/experiment.py`) run its steps as Prefect tasks.

`lint-imports` checks the split (the "pure-search" contract in pyproject.toml): the search
imports nothing of the campaign, the warehouse, the logs, the simulator or the monitors.
"""
