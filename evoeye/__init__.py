"""evoeye: self-evolving runtime monitoring of autonomous driving systems."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("evoeye")
except PackageNotFoundError:  # running from a source tree without an install
    __version__ = "0.0.0+local"
