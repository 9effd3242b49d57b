"""The README's Python example runs as written, saved as a script in a directory outside
the repository: it finds its scene (bundled with the package) and writes its picture,
or says plainly that matplotlib is missing."""

import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def readme_example() -> str:
    """The first ```python block of the README's "From Python" section, verbatim."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme[readme.index("## From Python") :]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def run_script(directory: pathlib.Path, *prelude: str) -> subprocess.CompletedProcess:
    """Saves the example as `cable.py` in `directory` and runs it there with this
    interpreter; `prelude` are statements run first (`-c`), the script unchanged."""
    assert ROOT not in directory.resolve().parents, "the directory is outside the repository"
    script = directory / "cable.py"
    script.write_text(readme_example(), encoding="utf-8")
    run = ["-c", "; ".join([*prelude, "exec(open('cable.py').read())"])] if prelude else ["cable.py"]
    return subprocess.run(
        [sys.executable, *run], cwd=directory, capture_output=True, text=True, timeout=600
    )


def test_readme_example_is_short():
    assert len(readme_example().strip().splitlines()) <= 15


def test_readme_example_writes_its_picture_from_anywhere(tmp_path):
    pytest.importorskip("matplotlib", reason='the picture needs matplotlib (pip install "./python[plot]")')
    done = run_script(tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("t = 2.00 s"), done.stdout
    assert done.stdout.rstrip().endswith("wrote cable.png"), done.stdout
    import matplotlib.pyplot as plt

    image = plt.imread(tmp_path / "cable.png")[..., :3]
    # The cable is drawn in matplotlib's first colour, C0 = #1f77b4.
    c0 = [0x1F / 255, 0x77 / 255, 0xB4 / 255]
    assert (abs(image - c0) < 0.05).all(axis=-1).sum() > 50, "the cable is drawn"


def test_readme_example_says_when_matplotlib_is_missing(tmp_path):
    # `None` in sys.modules makes `import matplotlib.pyplot` raise ImportError.
    done = run_script(tmp_path, "import sys", "sys.modules['matplotlib'] = None")
    assert done.returncode == 1, (done.stdout, done.stderr)
    assert done.stdout.startswith("t = 2.00 s"), done.stdout
    assert 'matplotlib is missing (pip install "./python[plot]")' in done.stderr
    assert not (tmp_path / "cable.png").exists()
