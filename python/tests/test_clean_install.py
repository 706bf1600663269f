"""``pip install ./python``, as the README says, leaves the checkout as it found it: the
build backend (flit_core) builds the wheel straight from ``src/motiond``, with no
``python/build/`` or ``*.egg-info`` left behind, untracked or ignored.

Installs into a virtual environment of its own with the running interpreter's pip
(``--python``; ``--no-deps``: iceoryx2 is not needed to check the build); pip fetches the
build backend from PyPI, or from its cache.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import List, Set

import pytest

# pip's words when it cannot fetch the build backend (no network and nothing cached).
_OFFLINE = (
    "No matching distribution found for flit_core",
    "Could not find a version that satisfies the requirement flit_core",
)


def porcelain(repo: Path) -> Set[str]:
    """``git status --porcelain`` of the checkout, ignored files included, one entry a
    line."""
    result = subprocess.run(
        ["git", "status", "--porcelain", "--untracked-files=all", "--ignored"],
        cwd=repo,
        capture_output=True,
        text=True,
        check=True,
    )
    return set(result.stdout.splitlines())


def in_tree(entries: Set[str], under: List[str]) -> Set[str]:
    """The entries whose path lies under one of ``under``."""
    return {entry for entry in entries if any(entry[3:].startswith(top) for top in under)}


def test_pip_install_of_the_package_leaves_the_checkout_clean(repo: Path, tmp_path: Path) -> None:
    try:
        subprocess.run(["git", "rev-parse", "--git-dir"], cwd=repo, capture_output=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout: nothing to compare")
    try:
        import venv  # noqa: F401
    except ImportError:
        pytest.skip(f"{sys.executable} cannot make a virtual environment (install python3-venv)")
    environment = tmp_path / "venv"
    # Without a pip of its own: this interpreter's pip installs into it (`--python`), which
    # saves bootstrapping one.
    made = subprocess.run(
        [sys.executable, "-m", "venv", "--without-pip", str(environment)],
        capture_output=True,
        text=True,
    )
    if made.returncode != 0:
        pytest.skip(f"python -m venv failed, so no install can be checked:\n{made.stderr}")
    # Only the package's own directory can gain build products; the rest of the checkout
    # is left to other tests running meanwhile.
    watched = ["python/"]
    before = in_tree(porcelain(repo), watched)
    installed = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "--python",
            str(environment / "bin" / "python"),
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "--no-deps",
            "./python",
        ],
        cwd=repo,
        capture_output=True,
        text=True,
    )
    if installed.returncode != 0 and "no such option: --python" in installed.stderr:
        pytest.skip("this pip is older than 22.3 (no --python): install a newer pip")
    if installed.returncode != 0 and any(words in installed.stderr for words in _OFFLINE):
        pytest.skip(f"pip could not fetch the build backend (no network?):\n{installed.stderr}")
    assert installed.returncode == 0, installed.stderr
    left = in_tree(porcelain(repo), watched) - before
    assert not left, "pip install ./python left in the checkout:\n" + "\n".join(sorted(left))
    # And the wheel was whole: the modules, the type marker, the command.
    packages = list(environment.glob("lib/python3*/site-packages/motiond"))
    assert packages, "motiond was not installed"
    for name in ("__init__.py", "client.py", "session.py", "ipc.py", "py.typed"):
        assert (packages[0] / name).is_file(), f"{name} missing from the installed package"
    assert (environment / "bin" / "motiond-py").is_file()
