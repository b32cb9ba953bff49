"""Install and pack anywhere: `mbfmu install --prefix P` gives one executable that packs
from an empty directory with no environment variable, and fmpy runs the FMU."""

import os
import subprocess

from fmpy import simulate_fmu

from fmu_helpers import MODELS, mbfmu


def test_installed_mbfmu_packs_from_an_empty_directory_and_fmpy_runs_the_fmu(tmp_path):
    prefix, work = tmp_path / "prefix", tmp_path / "work"
    work.mkdir()
    r = subprocess.run([str(mbfmu()), "install", "--prefix", str(prefix)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    env = {k: v for k, v in os.environ.items() if k != "MBFMU_LIB"}
    env["PATH"] = f"{prefix / 'bin'}:{env.get('PATH', '')}"
    (work / "pendulum.xml").write_text((MODELS / "pendulum.xml").read_text())
    r = subprocess.run(
        ["mbfmu", "pack", "pendulum.xml", "-o", "pendulum.fmu"], cwd=work, env=env, capture_output=True, text=True
    )
    assert r.returncode == 0, r.stderr
    res = simulate_fmu(str(work / "pendulum.fmu"), stop_time=0.5, output_interval=0.1)
    assert len(res) == 6 and abs(res["time"][-1] - 0.5) < 1e-12
