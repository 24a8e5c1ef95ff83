"""A public handle on one variable of a running program: `plc.ref("main.speed")`.

Drivers (Modbus, motion traces), test strategies and experiments use it instead of the PLC's
internals. A reference is resolved once: it stays valid while the program runs, and must be
made again after the program is reloaded (online change, warm restart), whose variables are
new objects.
"""

from __future__ import annotations

from typing import Any

from ..model import types as T
from .paths import read, write
from .process_image import Binding


class VarRef:
    """The variable at `path`: its declared type, its value, and its process-image binding."""

    __slots__ = ("path", "type", "_container", "_key", "_binding")

    def __init__(self, path: str, container: Any, key: Any, type_: T.Type, binding: Binding | None):
        self.path = path
        self.type = type_
        self._container = container
        self._key = key
        self._binding = binding

    def get(self) -> Any:
        """The value as the program stores it (no conversion: a STRUCT is its object, a TIME ns)."""
        return read(self._container, self._key)

    def set(self, value: Any) -> None:
        """A raw store of a value already in the program's representation (see values.from_python):
        no conversion, no range check, and the process image is not touched (see `binding`)."""
        write(self._container, self._key, value)

    @property
    def binding(self) -> Binding | None:
        """The process-image binding of a located variable (`AT %QW0`), or None."""
        return self._binding

    def __repr__(self) -> str:
        return f"VarRef({self.path!r}, {self.type})"
