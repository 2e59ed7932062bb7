"""evoeye: self-evolving runtime monitoring of autonomous driving systems."""

from typing import Any


def __getattr__(name: str) -> Any:
    # __version__ is looked up on first use: importlib.metadata costs ~0.1 s at start-up,
    # which `evoeye --help` should not pay.
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            found = version("evoeye")
        except PackageNotFoundError:  # running from a source tree without an install
            found = "0.0.0+local"
        globals()["__version__"] = found  # looked up once: ingest checks it for every log
        return found
    raise AttributeError(f"module 'evoeye' has no attribute {name!r}")
