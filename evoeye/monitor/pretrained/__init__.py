"""FusionMonitor versions shipped with evoeye: one per logical scenario, for the demo.

Each sub-folder is a version folder as training saves it (`model.pt`, `card.json`; see
`evoeye.monitor.registry`), made by `python -m evoeye.results.demo_monitors` (`make
demo-monitors`): its card says on which runs (scenario, seed, count) it was trained. `install`
copies one into a data root, where it loads, evaluates and evolves like a version trained there.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES
from evoeye.paths import DataRoot

PACKAGED = Path(__file__).resolve().parent


def packaged_cards(folder: Path = PACKAGED) -> dict[str, dict]:
    """Logical scenario → the card of the version shipped for it."""
    fusion = FAMILIES[DEFAULT_FAMILY]
    cards = [json.loads(p.read_text()) for p in sorted(folder.glob(f"*/{fusion.meta_file}"))]
    return {c["logical_scenario"]: c for c in cards}


def packaged_versions(folder: Path = PACKAGED) -> dict[str, str]:
    """Logical scenario → the version shipped for it."""
    return {scenario: card["version"] for scenario, card in packaged_cards(folder).items()}


def install(root: DataRoot, version: str, folder: Path = PACKAGED) -> str:
    """Copy a shipped version into `root`'s monitors (kept as it is if already there); its id.
    Loading it checks its weights against the card's sha256."""
    fusion = FAMILIES[DEFAULT_FAMILY]
    target = fusion.version_dir(root, version)
    if not target.exists():
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = target.with_name(f".{version}.installing")
        shutil.rmtree(tmp, ignore_errors=True)
        shutil.copytree(folder / version, tmp)
        tmp.rename(target)
    return version
