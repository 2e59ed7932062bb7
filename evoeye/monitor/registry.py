"""FusionMonitor versions on disk: `<root>/monitors/<version>/` with `model.pt` and `card.json`.

`model.pt` holds only the network config (plain types) and its state_dict (tensors, including
the input normalisers), loaded with `torch.load(weights_only=True)`: no pickled code runs. The
card records where the weights came from and how good they are (see `evoeye.monitor.train`),
plus the checkpoint's sha256, checked on load. A version id is `fusion-<hash>` of the weights
and of what produced them (config, hyper-parameters, data selection and fingerprint, parent),
never of the wall clock: the same seed on the same data gives the same version. Versions are
written once, atomically (a temporary folder renamed into place), and never modified. Reading
them (folders, cards, the checksum) is the fusion family's (`evoeye.monitor.families`).
"""

from __future__ import annotations

import hashlib
import io
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any

import orjson
import torch

from evoeye.monitor.card import thresholds_from_card
from evoeye.monitor.families import (
    DEFAULT_FAMILY,
    FAMILIES,
    MonitorLoadError,
    read_model,
)
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.model import FusionNet, config_from_dict
from evoeye.paths import DataRoot

FUSION = FAMILIES[DEFAULT_FAMILY]
MODEL_FILE = FUSION.model_file
CARD_FILE = FUSION.meta_file
VERSION_PREFIX = FUSION.prefix
HASHED_CARD_KEYS = ("config", "hyperparameters", "selection", "data", "parent", "horizon_s")


def _json(value: Any) -> bytes:
    return orjson.dumps(value, option=orjson.OPT_SORT_KEYS | orjson.OPT_SERIALIZE_NUMPY)


def checkpoint_bytes(net: FusionNet) -> bytes:
    """The model.pt bytes of a network: {"config": dict, "state_dict": tensors}."""
    buf = io.BytesIO()
    state = {k: v.detach().cpu().contiguous() for k, v in net.state_dict().items()}
    torch.save({"config": net.config.to_dict(), "state_dict": state}, buf)
    return buf.getvalue()


def version_of(net: FusionNet, card: dict[str, Any]) -> str:
    """`fusion-<12 hex>`: sha256 of the weights and the card's provenance fields."""
    h = hashlib.sha256()
    for name, tensor in sorted(net.state_dict().items()):
        h.update(name.encode())
        h.update(tensor.detach().cpu().contiguous().numpy().tobytes())
    h.update(_json({k: card.get(k) for k in HASHED_CARD_KEYS}))
    return VERSION_PREFIX + h.hexdigest()[:12]


def version_dir(root: DataRoot, version: str) -> Path:
    return FUSION.version_dir(root, version)


def _write(path: Path, data: bytes) -> None:
    with open(path, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())


def save_version(root: DataRoot, net: FusionNet,
                 card: dict[str, Any]) -> str:
    """Write a new version (model.pt + card.json) atomically; its id. An identical version
    already on disk is kept as it is (same id = same weights and provenance)."""
    version = version_of(net, card)
    final = version_dir(root, version)
    if final.exists():
        return version
    final.parent.mkdir(parents=True, exist_ok=True)
    model = checkpoint_bytes(net)
    card = {"version": version, **card, "model_sha256": hashlib.sha256(model).hexdigest()}
    tmp = Path(tempfile.mkdtemp(prefix=f".{version}.", dir=final.parent))
    try:
        _write(tmp / MODEL_FILE, model)
        _write(tmp / CARD_FILE, orjson.dumps(card, option=orjson.OPT_INDENT_2
                                             | orjson.OPT_SERIALIZE_NUMPY))
        try:
            os.rename(tmp, final)
        except OSError:
            if not final.exists():  # not a concurrent writer of the same version: a real error
                raise
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return version


def list_versions(root: DataRoot) -> list[str]:
    """Every complete version under the root, oldest card first."""
    return FUSION.versions(root)


def read_card(root: DataRoot, version: str) -> dict[str, Any]:
    """The card of a version (MonitorLoadError if it is missing or not JSON)."""
    return FUSION.read_meta(root, version)


def net_from_bytes(data: bytes, path: Path) -> FusionNet:
    """A FusionNet from model.pt bytes (read from `path`), weights only; MonitorLoadError on
    anything wrong."""
    try:
        ckpt = torch.load(io.BytesIO(data), map_location="cpu", weights_only=True)
        net = FusionNet(config_from_dict(ckpt["config"]))
        net.load_state_dict(ckpt["state_dict"], strict=True)
    except Exception as e:  # torch raises many kinds on bad bytes; all mean the same here
        raise MonitorLoadError(f"{path}: not a valid FusionMonitor checkpoint "
                               f"({type(e).__name__}: {e})") from e
    return net.eval()


def load_net(path: Path, expected_sha256: str | None = None) -> FusionNet:
    """A FusionNet from a model.pt, weights only, checked against `expected_sha256` if given;
    MonitorLoadError on anything wrong."""
    if expected_sha256 is None:
        try:
            data = path.read_bytes()
        except OSError as e:
            raise MonitorLoadError(f"{path}: cannot read checkpoint ({e.strerror or e})") from e
    else:
        data = read_model(path, path.with_name(CARD_FILE), {"model_sha256": expected_sha256})
    return net_from_bytes(data, path)


def decode_monitor(data: bytes, card: dict[str, Any], version: str) -> FusionMonitor:
    """The FusionMonitor of checked model.pt bytes and its card (eval mode, thresholds loaded)."""
    net = net_from_bytes(data, Path(FUSION.folder, version, MODEL_FILE))
    return FusionMonitor(net, version, thresholds_from_card(card), card)


def load_monitor(root: DataRoot, version: str) -> FusionMonitor:
    """The FusionMonitor of a saved version, ready to score (eval mode, thresholds loaded)."""
    return FUSION.load(root, version)
