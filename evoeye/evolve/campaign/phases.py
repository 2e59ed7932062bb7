"""Where a campaign's time goes: wall and CPU seconds per phase of its rounds, for profiling.

    simulate  propose and simulate the round's runs, writing their logs
    score     convert each new run as the warehouse does (from its Episode in memory, or the
              log a resumed round finds on disk) and score it with G_r
    ingest    put the round's runs into the warehouse
    train     the monitor update G_r → G_{r+1}
    refresh   every record's feedback under G_{r+1}
    assess    G_{r+1} on the Test Set and the Hard Set
    state     the campaign's state: rebuilding it, storing feedback and rounds
"""

from __future__ import annotations

from functools import partial

from evoeye.phases import PhaseClock as _Clock

PHASES = ("simulate", "score", "ingest", "train", "refresh", "assess", "state")
PhaseClock = partial(_Clock, PHASES)  # wall and CPU seconds (of this process) per phase
