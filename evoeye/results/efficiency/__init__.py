"""Sample efficiency: does a strategy's choice of runs teach the monitor faster than Uniform's?

Learning curves from a small initial set, judged on sets no strategy shaped (a large uniform
Test Set, a boundary set built once by bisection), pool-based screening with a greedy oracle
(a lower bound on what choosing runs can gain), and generative confirmation; per regime (a
logical scenario driven by an ADS profile).

    EfficiencyConfig                      what runs, at what size (config.py)
    prepare_regime(root, regime, config)  its data: pool, val, oracle and Test Sets, boundary set
    RegimeData.load(...)                  those sets' windows in memory (sets.py)
    run_curve(...)                        one learning curve of one strategy and seed (curves.py)
"""
