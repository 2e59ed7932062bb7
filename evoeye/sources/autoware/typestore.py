"""The ROS 2 message types of an Autoware recording: ROS 2 Humble's plus the vendored Autoware ones.

An MCAP bag embeds its definitions and is decoded with them (so a bag of older or newer
Autoware messages reads as recorded); a `.db3` bag of Humble embeds none and is decoded with
this store (`schemas/external/autoware/`, see its NOTICE). Converters are picked by type name
(`convert.CONVERTERS`), so the pre-2024 `autoware_auto_*` names dispatch to the same code.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

MSG_DIR = Path(__file__).resolve().parents[3] / "schemas" / "external" / "autoware"


def msg_files() -> dict[str, Path]:
    """Type name (`<package>/msg/<Type>`) → its vendored .msg file."""
    return {f"{p.parent.parent.name}/msg/{p.stem}": p for p in sorted(MSG_DIR.glob("*/msg/*.msg"))}


@cache
def typestore() -> Typestore:
    """ROS 2 Humble's types and the vendored Autoware ones, registered once."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types = {}
    for name, path in msg_files().items():
        types.update(get_types_from_msg(path.read_text(encoding="utf-8"), name))
    store.register(types)
    return store
