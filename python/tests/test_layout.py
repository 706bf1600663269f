"""The ctypes mirrors of ``motiond.ipc`` against the Rust contract.

The reference is what the Rust crate itself prints (``cargo run -p motion-ipc --example
layout``, fixture ``contract``): for every payload its size, alignment, iceoryx2 type name
and each field's name, offset, size and type; every enumeration's values, names and
texts; the flag bits; the constants; the service names.

How a change on the Rust side reaches these tests: the payloads are declared once, with
``payload!`` in ``crates/motion-ipc/src``, and the mirrors in ``motiond/_layout.py`` are
generated from that declaration (``scripts/gen``). Add a field ``pub spare: u32`` to
``AxisState`` and

1. ``crates/motion-ipc/tests/layout.rs`` fails to compile until its pinned sizes and
   offsets are updated, and ``crates/motion-ipc/tests/generated.rs`` fails ("stale
   generated files: include/motiond.h, python/src/motiond/_layout.py") until
   ``scripts/gen`` has rewritten the header and the mirrors;
2. before that, the example prints the new field, and ``test_payload_layouts`` fails:
   "AxisState: size 80 != 88", "AxisState: field #12 differs: rust {'name': 'spare',
   'offset': 80, 'size': 4, 'type': 'u32'}, python None", and the same for
   ``MotionFrame``, whose size and ``signals`` offset moved.

These tests check what the generator wrote (and that nobody edited it by hand): every size,
offset, type name, enum value and refusal message as ctypes computes it.
"""

from __future__ import annotations

import ctypes
import re
from typing import Any, Dict, List

import pytest

import motiond
from motiond import errors, ipc

_SCALARS = {
    ctypes.c_uint8: "u8",
    ctypes.c_uint16: "u16",
    ctypes.c_uint32: "u32",
    ctypes.c_uint64: "u64",
    ctypes.c_int64: "i64",
    ctypes.c_double: "f64",
}


def ctype_name(kind: Any) -> str:
    """A ctypes field type spelled as the Rust description spells it."""
    if kind in _SCALARS:
        return _SCALARS[kind]
    if isinstance(kind, type) and issubclass(kind, ctypes.Array):
        return f"{ctype_name(kind._type_)}[{kind._length_}]"
    if isinstance(kind, type) and issubclass(kind, ipc.Payload):
        return kind.__name__
    return f"<{kind!r}>"


def upper_snake(name: str) -> str:
    """``RampPosition`` → ``RAMP_POSITION``, ``EStop`` → ``E_STOP``."""
    return re.sub(r"(?<!^)(?=[A-Z])", "_", name).upper()


def mirror_fields(cls: type) -> List[Dict[str, Any]]:
    return [
        {
            "name": name,
            "offset": getattr(cls, name).offset,
            "size": getattr(cls, name).size,
            "type": ctype_name(kind),
        }
        for name, kind in cls._fields_
    ]


def test_every_rust_payload_has_a_mirror_and_no_other(contract: Dict[str, Any]) -> None:
    rust = [layout["rust"] for layout in contract["layouts"]]
    assert sorted(rust) == sorted(ipc.PAYLOADS), "payload types differ"


def test_payload_layouts(contract: Dict[str, Any]) -> None:
    problems = []
    for layout in contract["layouts"]:
        name = layout["rust"]
        cls = ipc.PAYLOADS.get(name)
        if cls is None:
            problems.append(f"{name}: no Python mirror")
            continue
        if cls.type_name() != layout["type_name"]:
            problems.append(f"{name}: type name {cls.type_name()!r} != {layout['type_name']!r}")
        if ctypes.sizeof(cls) != layout["size"]:
            problems.append(f"{name}: size {ctypes.sizeof(cls)} != {layout['size']}")
        if ctypes.alignment(cls) != layout["align"]:
            problems.append(f"{name}: alignment {ctypes.alignment(cls)} != {layout['align']}")
        mine = mirror_fields(cls)
        theirs = layout["fields"]
        for index in range(max(len(mine), len(theirs))):
            rust_field = theirs[index] if index < len(theirs) else None
            python_field = mine[index] if index < len(mine) else None
            if rust_field != python_field:
                problems.append(
                    f"{name}: field #{index} differs: rust {rust_field}, python {python_field}"
                )
    assert not problems, "\n".join(problems)


def test_iceoryx2_sees_the_rust_type_names(contract: Dict[str, Any]) -> None:
    # iceoryx2's Python binding takes the name from `type_name()`; this is what it sends.
    from iceoryx2 import get_type_name

    for layout in contract["layouts"]:
        assert get_type_name(ipc.PAYLOADS[layout["rust"]]) == layout["type_name"]


def test_enumerations_values_names_and_texts(contract: Dict[str, Any]) -> None:
    problems = []
    for item in contract["enums"]:
        cls = ipc.ENUMS.get(item["rust"])
        if cls is None:
            problems.append(f"{item['rust']}: no Python enumeration")
            continue
        want = {
            upper_snake(v["name"]) if not item["flags"] else v["name"]: v for v in item["variants"]
        }
        have = {member.name: member for member in cls}
        if sorted(want) != sorted(have):
            problems.append(f"{item['rust']}: members {sorted(have)} != {sorted(want)}")
            continue
        for name, variant in want.items():
            member = have[name]
            if int(member) != variant["value"]:
                problems.append(f"{item['rust']}.{name} = {int(member)} != {variant['value']}")
            if variant["text"] is not None and member.text != variant["text"]:
                problems.append(
                    f"{item['rust']}.{name} text {member.text!r} != {variant['text']!r}"
                )
    assert not problems, "\n".join(problems)


def test_reason_messages_are_the_servers(contract: Dict[str, Any]) -> None:
    reasons = next(e for e in contract["enums"] if e["rust"] == "Reason")
    assert len(reasons["variants"]) == len(motiond.Reason)
    for variant in reasons["variants"]:
        reason = motiond.Reason(variant["value"])
        assert reason.message == variant["text"]


def test_every_refusal_reason_has_its_exception(contract: Dict[str, Any]) -> None:
    reasons = next(e for e in contract["enums"] if e["rust"] == "Reason")
    for variant in reasons["variants"]:
        reason = motiond.Reason(variant["value"])
        if reason == motiond.Reason.ACCEPTED:
            assert reason not in errors.REFUSALS
            continue
        cls = errors.REFUSALS[reason]
        assert cls.__name__ == variant["name"]
        assert getattr(motiond, variant["name"]) is cls
        error = errors.refused(
            variant["value"], int(motiond.CommandKind.RAMP_POSITION), "axis x", 7
        )
        assert type(error) is cls and isinstance(error, motiond.Refused)
        assert error.reason is reason and error.tick == 7
        # The text reads like the Rust client's: "<kind> on <target> refused: <message>".
        assert str(error) == f"ramp-position on axis x refused: {variant['text']}"
    unknown = errors.refused(9999, 99, "axis x", 1)
    assert type(unknown) is motiond.Refused and unknown.reason == 9999


def test_constants_and_service_names(contract: Dict[str, Any]) -> None:
    for name, value in contract["constants"].items():
        assert getattr(ipc, name) == value, name
    assert ipc.SERVICES == contract["services"]
    assert ipc.service_name("demo", "frame") == "motiond/demo/frame"


def test_text_fields_read_like_rust() -> None:
    field = (ctypes.c_uint8 * 8)(*b"mm\0\0\0\0\0\0")
    assert ipc.read_text(field) == "mm"
    field = (ctypes.c_uint8 * 4)(ord("o"), ord("k"), 0xFF, ord("x"))
    assert ipc.read_text(field) == "ok"  # invalid UTF-8 ends the text, never raises


def test_a_device_model_is_named_by_its_id_or_else_its_code() -> None:
    device = ipc.DeviceInfo()
    device.model = 99  # no built-in board: DeviceModel does not know it
    device.model_id[:6] = list(b"widget")
    assert device.model_name() == "widget"
    assert ipc.to_enum(ipc.DeviceModel, device.model) == 99
    device.model_id[:] = [0] * ipc.MODEL_ID_LEN
    assert device.model_name() == "model 99"
    # Untrusted bytes, as the Rust side reads them: garbage falls back to the code; a full
    # field with no terminating zero is the id.
    for garbage, named in [
        (b"wid\x1bget", False),
        (b"two words", False),
        (b"\xff\xfe", False),
        (b"0123456789abcdef", True),
    ]:
        device.model_id[:] = list(garbage.ljust(ipc.MODEL_ID_LEN, b"\0"))
        expected = garbage.decode() if named else "model 99"
        assert device.model_name() == expected, garbage


def test_client_id_round_trips() -> None:
    value = 0x0123_4567_89AB_CDEF_FEDC_BA98_7654_3210
    client_id = ipc.ClientId.from_int(value)
    assert (client_id.lo, client_id.hi) == (0xFEDC_BA98_7654_3210, 0x0123_4567_89AB_CDEF)
    assert int(client_id) == value


@pytest.mark.parametrize("cls", list(ipc.PAYLOADS.values()), ids=list(ipc.PAYLOADS))
def test_copy_is_detached(cls: type) -> None:
    original = cls()
    duplicate = original.copy()
    assert bytes(duplicate) == bytes(original)
    assert ctypes.addressof(duplicate) != ctypes.addressof(original)


def test_a_group_status_carries_the_servers_receive_stamp() -> None:
    # GroupState.last_received_ns (schema 8): when the server took the last applied
    # setpoint from the setpoints service, on the clock of the frame's publish_ns.
    state = ipc.GroupState(
        last_sequence=7,
        last_applied_tick=99,
        last_received_ns=123_456_789,
        abort_axis=0xFFFF_FFFF,
    )
    assert state.last_received_ns == 123_456_789
    status = motiond.GroupStatus.of(ipc.ServerInfo(), 0, 100, state)
    assert (status.last_sequence, status.last_applied_tick) == (7, 99)
    assert status.last_received_ns == 123_456_789
