"""Shared fixtures: the repository's paths and the CLI binary the comparisons run."""

import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENES = sorted((ROOT / "scenes").glob("*.toml"))


@pytest.fixture(scope="session")
def cli():
    """The `splinerod` CLI built in release mode (built here if missing or stale)."""
    subprocess.run(
        ["cargo", "build", "--release", "--quiet", "--bin", "splinerod"],
        cwd=ROOT,
        check=True,
    )
    return ROOT / "target" / "release" / "splinerod"
