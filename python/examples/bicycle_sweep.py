"""The benchmark bicycle's lean/steer eigenvalues against forward speed (Meijaard et al.
2007, Fig. 3): pack models/benchmark_bicycle.xml, sweep the parameter v, plot.
Usage: python bicycle_sweep.py [OUT.png]"""

import sys
from pathlib import Path

import numpy as np

import mbfmu

ROOT = Path(__file__).resolve().parents[2]

if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("bicycle_sweep.png")
    fmu = mbfmu.pack(ROOT / "models" / "benchmark_bicycle.xml", Path("benchmark_bicycle.fmu"))
    s = mbfmu.sweep(fmu, "v", np.linspace(0.0, 10.0, 101), at=0.0, tolerance=1e-10, progress=True)
    ax = s.plot(out, title="Benchmark bicycle (Meijaard et al. 2007): eigenvalues against forward speed")
    ax.set_ylim(-10, 10)
    ax.figure.savefig(out, dpi=120, bbox_inches="tight")
    print(out)
