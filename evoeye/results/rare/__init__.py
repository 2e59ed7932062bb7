"""Testing efficiency in rare regimes: how many failures a strategy finds per simulated run,
how many distinct mechanisms, and how well its runs estimate the failure rate (`part.py`)."""
