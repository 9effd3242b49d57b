"""Shared fixtures: the repository's paths and the CLI binary the comparisons run."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENES = sorted((ROOT / "scenes").glob("*.toml"))


@pytest.fixture(scope="session")
def cli():
    """The `splinerod` CLI: `$SPLINEROD_CLI` if set (.ci/run sets the one its release
    tests built), else built here in release mode (a no-op when up to date)."""
    given = os.environ.get("SPLINEROD_CLI")
    if given:
        return pathlib.Path(given).resolve()
    subprocess.run(
        ["cargo", "build", "--release", "--quiet", "--bin", "splinerod"],
        cwd=ROOT,
        check=True,
    )
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return target / "release" / "splinerod"


def pytest_configure(config):
    """The `slow` mark: tests CI leaves out (`-m "not slow"`), run by a plain `pytest`."""
    config.addinivalue_line("markers", "slow: a slow case; CI runs the others")
