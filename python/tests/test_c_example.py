"""The C example (examples/c) against the session's live motiond.

It needs iceoryx2's C library, which no package registry carries: ``./scripts/test`` builds
and runs it only with ``MOTIOND_BUILD_C_EXAMPLE=1`` and ``IOX2_TARGET`` (see
examples/c/README.md), passing the binary in ``MOTIOND_C_EXAMPLE``. Without it this test
is skipped, and says so.
"""

from __future__ import annotations

import os
import subprocess

import pytest

from conftest import Server

EXAMPLE = os.environ.get("MOTIOND_C_EXAMPLE")


@pytest.mark.skipif(
    not EXAMPLE,
    reason="MOTIOND_C_EXAMPLE not set (build it with MOTIOND_BUILD_C_EXAMPLE=1 ./scripts/test)",
)
def test_c_example_reads_frames_and_commands(server: Server) -> None:
    assert EXAMPLE is not None
    result = subprocess.run(
        [EXAMPLE, server.name, "x", "35"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    output = result.stdout + result.stderr
    assert result.returncode == 0, output
    assert "read 200 frames" in output
    assert "ramp x to 35.000 mm: accepted" in output
    assert "refused: position outside the axis's min..max soft limits" in output
    assert "arrived at 35.000 mm" in output
