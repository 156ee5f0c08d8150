"""Where the tests find the suite scenes and the `ember` command (for bit-identity)."""

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def scenes_dir() -> Path:
    return Path(os.environ.get("EMBER_SCENES", REPO.parent / "shared" / "scenes"))


def ember_bin() -> Path:
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return Path(os.environ.get("EMBER_BIN", target / "release" / "ember"))


@pytest.fixture(scope="session")
def scenes() -> Path:
    d = scenes_dir()
    if not (d / "cornell-box" / "scene.xml").exists():
        pytest.fail(f"suite scenes not found in {d} (set EMBER_SCENES)")
    return d


@pytest.fixture(scope="session")
def cli() -> Path:
    b = ember_bin()
    if not b.exists():
        pytest.fail(f"the ember command is not built at {b} (cargo build --release -p ember-cli, or set EMBER_BIN)")
    return b
