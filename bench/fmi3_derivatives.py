"""FMI 3 derivatives of the N-link hanging chain (bench/chain_model.sh N hanging), through
fmpy's FMU3Slave: the gradient of the output tip_z over all 2N states, as one
fmi3GetAdjointDerivative call (one transposed solve of Eq. 34) against 2N
fmi3GetDirectionalDerivative calls (one solve per state column); both after the first
call at the point, which factors Eq. 34 (timed apart). Prints times and the ratio, and
checks the two gradients agree.

    .venv/bin/python bench/fmi3_derivatives.py [N ...]     (default 100 300)
"""

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

ROOT = Path(__file__).resolve().parents[1]


def chain_fmu(n: int, d: Path) -> Path:
    model = d / f"chain{n}.xml"
    model.write_text(
        subprocess.run(
            ["bash", str(ROOT / "bench/chain_model.sh"), str(n), "hanging"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    )
    fmu = d / f"chain{n}.fmu"
    subprocess.run(
        [
            str(ROOT / "target/release/mbfmu"),
            "pack",
            str(model),
            "-o",
            str(fmu),
            "--fmi",
            "3",
        ],
        check=True,
        capture_output=True,
    )
    return fmu


def run(n: int, d: Path) -> None:
    fmu = chain_fmu(n, d)
    md = read_model_description(str(fmu))
    f = FMU3Slave(
        guid=md.guid,
        unzipDirectory=extract(str(fmu)),
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="bench",
    )
    f.instantiate()
    f.enterInitializationMode(startTime=0.0)
    f.exitInitializationMode()
    states = [v for v in md.modelVariables if v.derivative is not None]
    knowns = [v.derivative.valueReference for v in states]
    tip = next(
        u.variable.valueReference for u in md.outputs if u.variable.name == "tip_z"
    )
    t0 = time.perf_counter()
    f.getAdjointDerivative([tip], knowns, [1.0], nSensitivity=len(knowns))
    factor = time.perf_counter() - t0
    t0 = time.perf_counter()
    row = np.array(
        f.getAdjointDerivative([tip], knowns, [1.0], nSensitivity=len(knowns))
    )
    adjoint = time.perf_counter() - t0
    t0 = time.perf_counter()
    cols = np.array([f.getDirectionalDerivative([tip], [k], [1.0])[0] for k in knowns])
    directional = time.perf_counter() - t0
    f.terminate()
    f.freeInstance()
    diff = np.abs(row - cols).max() / (1.0 + np.abs(cols).max())
    print(
        f"N = {n:5d}: {len(knowns)} states; first call (factor Eq. 34) {factor * 1e3:8.2f} ms; "
        f"output row by 1 adjoint call {adjoint * 1e3:8.3f} ms; by {len(knowns)} directional calls "
        f"{directional * 1e3:9.2f} ms; ratio {directional / adjoint:7.1f}; rel. difference {diff:.1e}"
    )


if __name__ == "__main__":
    sizes = [int(a) for a in sys.argv[1:]] or [100, 300]
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            run(n, Path(tmp))
