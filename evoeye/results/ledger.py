"""The results' ledger: every finished unit of work (a training, an evaluation) by its inputs.

`<root>/results/ledger/<kind>-<hash>.json` holds one unit: its kind, its inputs (everything that
determines the output: the recipe, the seed, the fingerprints of the runs it read) and its output
(a version id, or figures). A re-run of `evoeye results` asks the ledger first, so it trains,
evaluates and assesses only what is new; data added to a split changes that split's
fingerprint, and so every unit that read it is done again. Entries are written atomically and
never changed; an entry whose output no longer holds (a version folder removed) is done again.
"""

from __future__ import annotations

import hashlib
import json
from collections import Counter
from collections.abc import Callable
from typing import Any, TypeVar

from evoeye.atomic import atomic_file
from evoeye.paths import DataRoot

T = TypeVar("T")


def _canonical(inputs: Any) -> str:
    return json.dumps(inputs, sort_keys=True, default=str, separators=(",", ":"))


class Ledger:
    """Finished units under a data root, with counts of what this run found and computed."""

    def __init__(self, root: DataRoot) -> None:
        self.folder = root.path / "results" / "ledger"
        self.found: Counter[str] = Counter()  # kind → units found done
        self.computed: Counter[str] = Counter()  # kind → units done now

    def path(self, kind: str, inputs: Any):
        digest = hashlib.sha256(f"{kind}\n{_canonical(inputs)}".encode()).hexdigest()[:20]
        return self.folder / f"{kind}-{digest}.json"

    def get(self, kind: str, inputs: Any) -> Any | None:
        """The output of a finished unit, or None."""
        path = self.path(kind, inputs)
        if not path.is_file():
            return None
        entry = json.loads(path.read_bytes())
        # a hash collision or a hand-edited file: not this unit
        return entry["output"] if entry.get("inputs") == json.loads(_canonical(inputs)) else None

    def put(self, kind: str, inputs: Any, output: Any) -> None:
        self.folder.mkdir(parents=True, exist_ok=True)
        entry = {"kind": kind, "inputs": json.loads(_canonical(inputs)), "output": output}
        with atomic_file(self.path(kind, inputs)) as f:
            f.write(json.dumps(entry, indent=1, default=float).encode())

    def remember(self, kind: str, inputs: Any, compute: Callable[[], T],
                 valid: Callable[[T], bool] | None = None) -> T:
        """The unit's output (JSON types): found in the ledger (if still `valid`), else
        computed and kept."""
        output = self.get(kind, inputs)
        if output is not None and (valid is None or valid(output)):
            self.found[kind] += 1
            return output
        output = json.loads(json.dumps(compute(), default=float))  # as a re-run reads it
        self.put(kind, inputs, output)
        self.computed[kind] += 1
        return output
