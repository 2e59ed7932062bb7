"""The simulator: a concrete scenario and a seed in, an Episode (frames, outcome) out.

`runner.run_episode(spec)` builds the logical scenario's world (its `ScenarioSpec.world`), drives
the ADS in it and records every frame; nothing here writes a file (the log layer does).
"""
