"""Commissioning from Python against a live motiond of its own (the simulated robot of
``config/sim.toml``): the QUADpack to a new address and the SIXpack to 115200 baud with the
device's claims held, refusals without them, for a board without the setting, for an
unknown device and for a value the board does not take."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterator

import pytest

import motiond
from conftest import Server, start_server


@pytest.fixture(scope="module")
def own_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """A server of this module's own: commissioning changes its boards."""
    tmp: Path = tmp_path_factory.mktemp("commission")
    instance = start_server(tmp, f"pytest-commission-{os.getpid()}")
    yield instance
    assert instance.stop() == 0, instance.log_text()


def test_commission_address_and_rate(own_server: Server) -> None:
    with motiond.Client(own_server.name, timeout=5.0) as client:
        with pytest.raises(motiond.NotClaimed):
            client.commission("pack_aux", address=5)
        with pytest.raises(motiond.NoSuchDevice):
            client.commission("no_such", address=5)
        with pytest.raises(ValueError):
            client.commission("pack_aux", address=5, baud=115200)
        with client.claim_device("pack_aux") as claim:
            assert claim.active
            accepted = client.commission("pack_aux", address=5)
            found = client.wait_commissioned("pack_aux", accepted, timeout=5.0)
        assert isinstance(found, motiond.Commissioned)
        assert found.address == 5 and found.firmware.startswith("QUADpack"), found
        with client.claim_device("pack_xyz"):
            with pytest.raises(motiond.OutOfRange):
                client.commission("pack_xyz", address=5)  # pack_aux has it now
            with pytest.raises(motiond.OutOfRange):
                client.commission("pack_xyz", baud=230400)  # $40 cannot make it
            accepted = client.commission("pack_xyz", baud=115200)
            found = client.wait_commissioned("pack_xyz", accepted, timeout=5.0)
        assert found.address == 1
        with client.claim_device("feeder_qsb"):
            with pytest.raises(motiond.Unsupported):
                client.commission("feeder_qsb", address=3)
        client.wait_ready(timeout=10.0)
