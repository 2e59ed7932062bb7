"""Every trained monitor version of a data root, described from its card: `evoeye monitors`.

A row per version of every registered family (the FusionMonitor's, and the trained baselines'
once `evoeye.baselines` is imported): its scenario, family, parent (a fine-tuned version's),
what it was trained on, its validation figures where its card records them, and the campaign
rounds whose monitor it is (campaign_rounds).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from evoeye.monitor.families import FAMILIES, MonitorLoadError
from evoeye.paths import DataRoot


@dataclass(frozen=True)
class MonitorRow:
    """One version as `evoeye monitors` lists it (None: its card does not say)."""

    version: str
    family: str
    logical_scenario: str | None
    parent: str | None
    train_runs: int | None
    train_frames: int | None  # windows it was trained on
    created_at: str | None
    val_auroc: float | None
    val_auprc: float | None
    val_f1: float | None  # at the threshold for target FPR 0.05
    path: str
    rounds: tuple[str, ...] = ()  # "G_<r> of <campaign id>" for each campaign round it is

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _train_size(card: dict[str, Any]) -> tuple[int | None, int | None]:
    """(runs, frames) a card says its version was trained on (either family's keys)."""
    data = card.get("data", {}).get("train", {})
    return (data.get("runs", card.get("train_scenarios")),
            data.get("frames", card.get("train_windows")))


def describe(family: str, version: str, card: dict[str, Any], path: str,
             rounds: tuple[str, ...] = ()) -> MonitorRow:
    val = card.get("metrics", {}).get("val", {})
    runs, frames = _train_size(card)
    return MonitorRow(version, family, card.get("logical_scenario"), card.get("parent"), runs,
                      frames, card.get("created_at"), val.get("auroc"), val.get("auprc"),
                      val.get("fpr_0.05", {}).get("f1"), path, rounds)


def campaign_roles(root: DataRoot) -> dict[str, tuple[str, ...]]:
    """version → "G_<r> of <campaign id>" for every stored campaign round."""
    from evoeye.store.feedback import read_rounds

    roles: dict[str, tuple[str, ...]] = {}
    for row in read_rounds(root):
        roles[row.monitor_version] = (*roles.get(row.monitor_version, ()),
                                      f"G_{row.round} of {row.campaign_id}")
    return roles


def list_monitors(root: DataRoot, scenario: str | None = None) -> list[MonitorRow]:
    """Every readable version under `root` (optionally of one logical scenario), by family
    and then oldest card first; an unreadable card is skipped (loading it names the problem)."""
    rows, roles = [], campaign_roles(root)
    for name, family in FAMILIES.items():
        mine = []
        for version in family.versions(root):
            try:
                card = family.read_meta(root, version)
            except MonitorLoadError:
                continue
            if scenario in (None, card.get("logical_scenario")):
                mine.append(describe(name, version, card, str(family.version_dir(root, version)),
                                     roles.get(version, ())))
        rows += sorted(mine, key=lambda r: (r.created_at or "", r.version))
    return rows
