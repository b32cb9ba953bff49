"""Helpers of the FMU tests (test_fmu_*.py): locate and run the mbfmu binary, pack
models, create fmpy FMU2Slave instances, capture the FMU's log messages, drive a
Co-Simulation loop.

The binary is found exactly as in test_model_description.py: $MBFMU_BIN, else
$CARGO_TARGET_DIR/release/mbfmu, else <repo>/target/release/mbfmu.
"""

import csv
import os
import subprocess
from ctypes import CDLL, CFUNCTYPE, Structure, c_char_p, c_int, c_size_t, c_void_p, cast
from dataclasses import dataclass
from pathlib import Path

from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave, defaultCallbacks, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "models"


def mbfmu() -> Path:
    if "MBFMU_BIN" in os.environ:
        return Path(os.environ["MBFMU_BIN"])
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return target / "release" / "mbfmu"


def run_mbfmu(*args: str) -> subprocess.CompletedProcess:
    exe = mbfmu()
    assert exe.is_file(), f"{exe} is missing: run `cargo build --release` first"
    return subprocess.run([str(exe), *args], capture_output=True, text=True, cwd=ROOT)


@dataclass
class Packed:
    """A packed FMU: the zip, the same files unzipped, and its model description."""

    model: Path
    fmu: Path
    unzipped: Path
    md: object

    @property
    def vr(self) -> dict:
        return {v.name: v.valueReference for v in self.md.modelVariables}

    @property
    def outputs(self) -> list:
        return [v.name for v in self.md.modelVariables if v.causality == "output"]

    @property
    def output_vrs(self) -> list:
        return [v.valueReference for v in self.md.modelVariables if v.causality == "output"]


def pack_model(model: Path, dest: Path) -> Packed:
    """`mbfmu pack model -o dest/<stem>.fmu --out-dir dest/<stem>`."""
    fmu = dest / f"{model.stem}.fmu"
    unzipped = dest / model.stem
    r = run_mbfmu("pack", str(model), "-o", str(fmu), "--out-dir", str(unzipped))
    assert r.returncode == 0, r.stderr
    return Packed(model, fmu, unzipped, read_model_description(str(fmu)))


def simulate_cli(model: Path, out: Path, end: float, step: float, tol: float) -> tuple[list, list]:
    """`mbfmu simulate`: (header, rows of floats)."""
    r = run_mbfmu(
        "simulate", str(model), "--end", repr(end), "--step", repr(step), "--tol", repr(tol), "--out", str(out)
    )
    assert r.returncode == 0, r.stderr
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(x) for x in row] for row in rows[1:]]


# --- log capture --------------------------------------------------------------------

# mbfmu calls the (variadic) fmi2CallbackLogger as logger(env, name, status, category,
# "%s", text). On the x86-64 and AArch64 Linux ABIs the variadic pointer argument is passed
# like a sixth fixed one, so a six-argument callback receives the text unformatted (and
# lets the tests check the "%s" contract). fmpy's own proxy (fmpy.logging.addLoggerProxy)
# would do the formatting, but it keeps the Python logger in one process-wide variable.
_Logger6 = CFUNCTYPE(None, c_void_p, c_char_p, c_int, c_char_p, c_char_p, c_char_p)


class LogCapture:
    """fmi2CallbackFunctions whose logger records (instance, status, category, format, text)."""

    def __init__(self):
        self.records: list[tuple[str, int, str, str, str]] = []

        def log(env, name, status, category, fmt, text):
            dec = lambda b: b.decode("utf-8") if b is not None else None  # noqa: E731
            self.records.append((dec(name), status, dec(category), dec(fmt), dec(text)))

        self._fn = _Logger6(log)  # kept alive as long as the capture
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = cast(self._fn, fmi2CallbackLoggerTYPE)
        self.callbacks.allocateMemory = defaultCallbacks.allocateMemory
        self.callbacks.freeMemory = defaultCallbacks.freeMemory

    def messages(self, status: int | None = None) -> list[str]:
        return [r[4] for r in self.records if status is None or r[1] == status]

    def clear(self):
        self.records.clear()


# --- instances ----------------------------------------------------------------------


def new_slave(
    p: Packed, name: str = "inst", unzipped: Path | None = None, log: LogCapture | None = None, logging_on: bool = False
) -> FMU2Slave:
    """An instantiated FMU2Slave (each loads the shared library of its unzip directory)."""
    s = FMU2Slave(
        guid=p.md.guid,
        unzipDirectory=str(unzipped or p.unzipped),
        modelIdentifier=p.md.coSimulation.modelIdentifier,
        instanceName=name,
    )
    s.instantiate(loggingOn=logging_on, callbacks=None if log is None else log.callbacks)
    return s


def initialize(
    s: FMU2Slave, tol: float, start: float = 0.0, stop: float | None = None, values: dict | None = None
) -> None:
    """setupExperiment, the values (vr -> value) in initialization mode, exit."""
    s.setupExperiment(tolerance=tol, startTime=start, stopTime=stop)
    s.enterInitializationMode()
    if values:
        s.setReal(list(values), list(values.values()))
    s.exitInitializationMode()


def steps(s: FMU2Slave, vrs: list, t0: float, h: float, n: int) -> list:
    """n doSteps of size h from t0, communication points t0 + k h; outputs after each."""
    rows = []
    for k in range(n):
        t = t0 + k * h
        s.doStep(currentCommunicationPoint=t, communicationStepSize=t0 + (k + 1) * h - t)
        rows.append(s.getReal(vrs))
    return rows


def run_alone(p: Packed, tol: float, h: float, n: int, name: str = "alone", unzipped: Path | None = None) -> list:
    """A whole run of a fresh instance: outputs at t = h, 2h, ..., nh."""
    s = new_slave(p, name, unzipped)
    try:
        initialize(s, tol)
        return steps(s, p.output_vrs, 0.0, h, n)
    finally:
        s.terminate()
        s.freeInstance()


_MALLINFO2_FIELDS = "arena ordblks smblks hblks hblkhd usmblks fsmblks uordblks fordblks keepcost".split()


class _Mallinfo2(Structure):
    _fields_ = [(name, c_size_t) for name in _MALLINFO2_FIELDS]


def heap_bytes() -> int:
    """Bytes malloc has handed out in this process and not got back (glibc mallinfo2:
    arena chunks in use plus mmapped chunks): counted by the allocator, unlike the
    resident set, which moves with pages. The FMU's library allocates through malloc."""
    mallinfo2 = CDLL(None).mallinfo2  # glibc >= 2.33
    mallinfo2.restype = _Mallinfo2
    m = mallinfo2()
    return m.uordblks + m.hblkhd
