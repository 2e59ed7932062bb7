"""Performance benchmarks: run `python -m benchmarks` (or `make bench`); results go to BENCHMARKS.md."""
