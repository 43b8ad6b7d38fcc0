"""Shared fixtures: the repository root and the `lustre` binary the Python values are
compared with (LUSTRE_BIN, else target/debug/lustre, built here when missing)."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SURFACES = ROOT / "data" / "surfaces"


@pytest.fixture(scope="session")
def lustre_bin() -> Path:
    env = os.environ.get("LUSTRE_BIN")
    if env:
        return Path(env)
    path = ROOT / "target" / "debug" / "lustre"
    if not path.exists():
        subprocess.run(["cargo", "build", "--bin", "lustre"], cwd=ROOT, check=True)
    return path


@pytest.fixture(scope="session")
def cli(lustre_bin):
    """Runs the CLI from the repository root; returns stdout (fails on a non-zero exit)."""

    def run(*args: str, input: str | None = None) -> str:
        p = subprocess.run(
            [str(lustre_bin), *args], cwd=ROOT, input=input, capture_output=True, text=True
        )
        assert p.returncode == 0, f"lustre {' '.join(args)}: {p.stderr}"
        return p.stdout

    return run


@pytest.fixture(autouse=True)
def at_root(monkeypatch):
    """Relative paths (data/surfaces/…, scenes/…) as the CLI runs see them."""
    monkeypatch.chdir(ROOT)


def loads_lines(text: str) -> list[dict]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]
