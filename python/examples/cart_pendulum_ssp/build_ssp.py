"""Build cart_pendulum_pid.ssp: pack plant.xml and pid.xml with mbfmu and zip them with
SystemStructure.ssd. Usage: python build_ssp.py [OUT.ssp]; then e.g.

    import fmpy.ssp.simulation, mbfmu
    fmpy.ssp.simulation.simulate_ssp("cart_pendulum_pid.ssp", stop_time=5, step_size=1e-3)
    mbfmu.linearize_system("cart_pendulum_pid.ssp", at=[0, 1])
"""

import sys
import tempfile
import zipfile
from pathlib import Path

import mbfmu

HERE = Path(__file__).resolve().parent


def build(out: Path) -> Path:
    """Write the SSP to `out` and return it."""
    with tempfile.TemporaryDirectory() as tmp:
        plant = mbfmu.pack(HERE / "plant.xml", Path(tmp) / "plant.fmu")
        pid = mbfmu.pack(HERE / "pid.xml", Path(tmp) / "pid.fmu")
        with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
            z.write(HERE / "SystemStructure.ssd", "SystemStructure.ssd")
            z.write(plant, "resources/plant.fmu")
            z.write(pid, "resources/pid.fmu")
    return out


if __name__ == "__main__":
    print(build(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("cart_pendulum_pid.ssp")))
