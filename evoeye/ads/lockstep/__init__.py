"""The ADS's stages over a batch of runs stepped in lockstep (`evoeye.sim.lockstep`).

Each batched stage does its array work once for every run of the batch and gives every run
exactly what the per-run module gives it, bit for bit, its random streams advanced the same way:
the per-run modules stay the reference, and the two engines write the same logs.
"""
