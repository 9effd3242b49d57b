"""The README's Python example runs as written (from the repository root)."""

import os
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_readme_python_example_runs(tmp_path, capsys):
    readme = (ROOT / "README.md").read_text()
    section = readme[readme.index("## From Python") :]
    block = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    assert len(block.strip().splitlines()) <= 15
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        exec(compile(block.replace('"cable.png"', repr(str(tmp_path / "cable.png"))), "README", "exec"), {})
    finally:
        os.chdir(cwd)
    printed = capsys.readouterr().out
    assert printed.startswith("t = 2.00 s")
