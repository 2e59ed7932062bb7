"""Registries of what users extend (logical scenarios, baselines), filled once on first use.

As highway-env registers an environment and pytest finds a plugin: every module of a built-in
package that declares the registry's attribute (e.g. `SCENARIO`) is registered, then every
object of the registry's entry point group (`[project.entry-points."evoeye.scenarios"]` in a
third-party package's pyproject.toml). Nothing else lists them: every list of scenarios or
baselines in evoeye is read from its registry. Reading is lazy, so that importing a registry
costs no entry point scan, and a built-in module is imported only when the registry is read.
"""

from __future__ import annotations

import functools
import pkgutil
from collections.abc import Callable, Iterator, Mapping
from importlib import import_module
from typing import Any, Generic, Protocol, TypeVar


class Named(Protocol):
    @property
    def name(self) -> str: ...


T = TypeVar("T", bound=Named)
V = TypeVar("V")


class RegistryError(ValueError):
    """A name registered twice, or an entry point that declares nothing."""


class UnknownNameError(RegistryError, KeyError):
    """A name not registered (a KeyError too, so `registry.get(name)` works)."""

    def __str__(self) -> str:
        return str(self.args[0])


@functools.cache
def _entry_points() -> Any:
    """Every installed package's entry points, read once per process (one scan of sys.path
    for all registries)."""
    from importlib.metadata import entry_points

    return entry_points()


class Registry(Mapping[str, T], Generic[T]):
    """Name → declaration, in registration order: the built-ins (modules in name order, or by
    `order` of the declaration when given), then the entry points (in name order), then whatever
    `register` added."""

    def __init__(self, kind: str, *, package: str, attr: str, group: str, cls: type,
                 order: Callable[[T], int] | None = None) -> None:
        self.kind, self.package, self.attr, self.group, self.cls = kind, package, attr, group, cls
        self.order = order
        self._items: dict[str, T] = {}
        self._loaded = False

    # -- filling -----------------------------------------------------------------------------
    def register(self, item: T) -> T:
        """Add one declaration; a second one under a taken name is an error."""
        if not isinstance(item, self.cls):
            raise RegistryError(f"a {self.kind} must be a {self.cls.__name__}, got {item!r}")
        known = self._items.get(item.name)
        if known is not None and known is not item:
            raise RegistryError(f"{self.kind} {item.name!r} is registered twice")
        self._items[item.name] = item
        return item

    def _declared(self, source: Any, where: str) -> list[T]:
        """The declarations an object holds: itself, a tuple of them, or a module's `attr`."""
        found = getattr(source, self.attr, source) if not isinstance(source, self.cls) else source
        items = list(found) if isinstance(found, tuple | list) else [found]
        if not items or not all(isinstance(i, self.cls) for i in items):
            raise RegistryError(f"{where} declares no {self.cls.__name__} (give one, a tuple "
                                f"of them, or a module with {self.attr})")
        return items

    def _load(self) -> None:
        if self._loaded:
            return
        self._loaded = True  # first, so that a plugin reading the registry while it loads works
        try:
            self._load_all()
        except BaseException:
            self._items.clear()  # no half-filled registry: the next read raises again
            self._loaded = False
            raise

    def _load_all(self) -> None:
        package = import_module(self.package)
        builtin: list[T] = []
        for info in sorted(pkgutil.iter_modules(package.__path__), key=lambda m: m.name):
            module = import_module(f"{self.package}.{info.name}")
            if hasattr(module, self.attr):
                builtin += self._declared(module, module.__name__)
        for item in sorted(builtin, key=self.order) if self.order else builtin:
            self.register(item)
        for ep in sorted(_entry_points().select(group=self.group), key=lambda e: e.name):
            for item in self._declared(ep.load(), f"entry point {ep.name} = {ep.value}"):
                self.register(item)

    def reload(self) -> None:
        """Forget everything and read the built-ins and entry points again (after a package
        was installed in this process)."""
        _entry_points.cache_clear()
        self._items.clear()
        self._loaded = False
        self._load()

    # -- reading -----------------------------------------------------------------------------
    def __getitem__(self, name: str) -> T:
        self._load()
        try:
            return self._items[name]
        except KeyError:
            raise UnknownNameError(self.unknown(name)) from None

    def __iter__(self) -> Iterator[str]:
        self._load()
        return iter(list(self._items))

    def __len__(self) -> int:
        self._load()
        return len(self._items)

    def __contains__(self, name: object) -> bool:
        self._load()
        return name in self._items

    def __setitem__(self, name: str, item: T) -> None:
        """Replace a declaration (tests: a broken world builder)."""
        self._load()
        self._items[name] = item

    def __delitem__(self, name: str) -> None:
        self._load()
        del self._items[name]

    def unknown(self, name: str) -> str:
        """The one-line error for a name not registered, naming the known ones."""
        return f"unknown {self.kind} {name!r}; known: {', '.join(self) or 'none'}"


class View(Mapping[str, V], Generic[V]):
    """A registry's names → one part of each declaration (e.g. a scenario's space), read
    through to the registry (so a declaration added later is in it)."""

    def __init__(self, registry: Registry[Any], part: Callable[[Any], V]) -> None:
        self.registry, self.part = registry, part

    def __getitem__(self, name: str) -> V:
        return self.part(self.registry[name])

    def __iter__(self) -> Iterator[str]:
        return iter(self.registry)

    def __len__(self) -> int:
        return len(self.registry)

    def __contains__(self, name: object) -> bool:
        return name in self.registry
