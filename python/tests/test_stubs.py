"""The type stubs match the compiled module (mypy's stubtest), so editors complete what
exists with the right parameters."""

import subprocess
import sys

import pytest

pytest.importorskip("mypy", reason="stubtest comes with mypy (installed by .ci/run)")


def test_stubs_match_the_module():
    done = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "splinerod._splinerod"],
        capture_output=True,
        text=True,
    )
    errors = [line for line in done.stdout.splitlines() if line.startswith("error:")]
    # PEP 800's @disjoint_base is not yet in typing for Python 3.9 to 3.14.
    real = [e for e in errors if "disjoint base" not in e]
    assert not real, done.stdout
