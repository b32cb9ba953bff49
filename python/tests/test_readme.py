"""The README's Python example runs as written (from the repository root, in a copy)."""

import re
import shutil
import subprocess
import sys

from conftest import ROOT


def test_readme_python_example_runs(tmp_path):
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## Python") :]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    assert len(code.strip().splitlines()) <= 12
    shutil.copytree(ROOT / "models", tmp_path / "models")
    (tmp_path / "example.py").write_text(code)
    r = subprocess.run([sys.executable, "example.py"], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert "Damping Ratio" in r.stdout
    for f in ("bode.png", "lin.mat", "bicycle.png", "cart_pendulum_pid.fmu", "bicycle.fmu"):
        assert (tmp_path / f).stat().st_size > 0, f
