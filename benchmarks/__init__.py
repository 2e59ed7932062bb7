"""Performance benchmarks: `python -m benchmarks` (or `make bench`); figures go to BENCHMARKS.md."""
