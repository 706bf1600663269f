"""What the generated mirrors of the contract (``_layout.py``) build on.

``_layout.py`` is generated from the Rust description of the contract; the classes here are
written by hand: the :class:`Payload` base of every ctypes mirror, the :class:`TextedEnum`
base of every enumeration, :func:`read_text`, and the few methods some mirrors carry
(``ClientIdMethods``, ``AxisInfoMethods``, ``DeviceInfoMethods``, ``ReasonMethods``: the
generator names them in ``crates/motion-ipc/src/schema/python.rs``).
"""

from __future__ import annotations

import ctypes
import enum
from typing import Optional, Type, TypeVar

P = TypeVar("P", bound="Payload")
C = TypeVar("C", bound="ClientIdMethods")


def read_text(field: "ctypes.Array[ctypes.c_uint8]") -> str:
    """Reads a zero-padded UTF-8 field: stops at the first zero byte; bytes that are not
    valid UTF-8 end the text there (as the Rust side reads them)."""
    data = bytes(field)
    end = data.find(b"\0")
    if end >= 0:
        data = data[:end]
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        return data[: error.start].decode("utf-8")


class Payload(ctypes.Structure):
    """Base of every payload mirror: the iceoryx2 type name and a few helpers."""

    _type_name_: str = ""

    @classmethod
    def type_name(cls) -> str:
        """The iceoryx2 type name, identical to the Rust ``#[type_name(..)]``."""
        return cls._type_name_

    def copy(self: P) -> P:
        """A private copy (detached from shared memory, writable)."""
        return type(self).from_buffer_copy(self)

    def text(self, field: str) -> str:
        """The zero-padded UTF-8 text field ``field`` as ``str``."""
        return read_text(getattr(self, field))

    def __repr__(self) -> str:
        parts = []
        for entry in self._fields_:
            name, kind = entry[0], entry[1]
            value = getattr(self, name)
            if isinstance(value, ctypes.Array):
                element = getattr(kind, "_type_", None)
                if element is ctypes.c_uint8:
                    value = read_text(value)
                else:
                    value = f"[{len(value)} × {getattr(element, '__name__', '?')}]"
            parts.append(f"{name}={value!r}")
        return f"{type(self).__name__}({', '.join(parts)})"


class TextedEnum(enum.IntEnum):
    """An enumeration whose values may have a text (a name the CLI prints, or a message).

    A member is declared ``NAME = value`` or ``NAME = value, "text"``; its value is the
    integer either way."""

    _text: Optional[str]

    def __new__(cls, value: int, text: Optional[str] = None) -> "TextedEnum":
        member = int.__new__(cls, value)
        member._value_ = value
        member._text = text
        return member

    @property
    def text(self) -> str:
        """The text the Rust side gives this value (``name()``, ``message()``, ``id()``), or
        the member name in lower case where it has none."""
        return self._text if self._text is not None else self.name.lower()


class ClientIdMethods:
    """``ClientId``: conversion from and to the node id value (a u128)."""

    lo: int
    hi: int

    @classmethod
    def from_int(cls: Type[C], value: int) -> C:
        """From a node id value (``node.id.value``)."""
        mask = 0xFFFF_FFFF_FFFF_FFFF
        return cls(value & mask, (value >> 64) & mask)  # type: ignore[call-arg]

    def __int__(self) -> int:
        return (self.hi << 64) | self.lo


class AxisInfoMethods:
    """``AxisInfo``: what the axis accepts."""

    capabilities: int

    def supports(self, kind: int) -> bool:
        """Whether the axis accepts commands of ``kind`` (a ``CommandKind``)."""
        return bool(self.capabilities & (1 << int(kind)))


class DeviceInfoMethods:
    """``DeviceInfo``: the model's name."""

    model: int
    model_id: "ctypes.Array[ctypes.c_uint8]"

    def model_name(self) -> str:
        """The model's config id as the server wrote it (any board, built in or not), or
        ``model <code>`` when the id is empty or not printable ASCII (as the Rust
        ``DeviceInfo::model_name``)."""
        model_id = read_text(self.model_id)
        if model_id and all(0x21 <= ord(char) <= 0x7E for char in model_id):
            return model_id
        return f"model {self.model}"


class ReasonMethods:
    """``Reason``: the server's message."""

    text: str

    @property
    def message(self) -> str:
        """One line saying what is wrong and what to do (the server's text)."""
        return self.text
