"""`pack(model, out)`: build a model file's FMU with the `mbfmu` command-line tool.

The tool is found as $MBFMU_BIN, else `mbfmu` on PATH, else the build of the repository
this package sits in (`target/release/mbfmu`, as after `cargo build --release`).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import warnings
from pathlib import Path

from .errors import ArgumentError, FMUNotFoundError, MbfmuError

_REPO = Path(__file__).resolve().parents[2]


class PackWarning(UserWarning):
    """The FMU was packed but lacks something, e.g. linearization states because they could
    not be selected at the model's start (the message says why, located in the model file)."""


def cli() -> Path:
    """Path of the `mbfmu` executable."""
    env = os.environ.get("MBFMU_BIN")
    if env:
        if not Path(env).is_file():
            raise MbfmuError(f"MBFMU_BIN={env} is not a file")
        return Path(env)
    target = Path(os.environ.get("CARGO_TARGET_DIR", _REPO / "target")) / "release" / "mbfmu"
    if target.is_file():
        return target
    found = shutil.which("mbfmu")
    if found:
        return Path(found)
    raise MbfmuError(
        "the mbfmu command-line tool was not found: build it with `cargo build --release` in the repository, "
        "put it on PATH, or set MBFMU_BIN"
    )


def set_args(start_values) -> list[str]:
    """`--set name=value` arguments of the tool for {name: value}; ArgumentError for a
    value that is not a number."""
    args = []
    for name, value in (start_values or {}).items():
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ArgumentError(f"start value of '{name}': {value!r} is not a number") from None
        # repr of a float reads back exactly in the tool (Rust's f64 parser).
        args += ["--set", f"{name}={number!r}"]
    return args


def run_cli(args: list[str], command: str) -> subprocess.CompletedProcess:
    """Run the tool; its usage and model errors (exit 2) are ArgumentError with its
    message, any other failure MbfmuError."""
    r = subprocess.run(args, capture_output=True, text=True)
    if r.returncode == 2:
        raise ArgumentError(r.stderr.strip())
    if r.returncode != 0:
        raise MbfmuError(f"mbfmu {command} failed (exit {r.returncode}): {r.stderr.strip()}")
    return r


def pack(model, out=None, out_dir=None, start_values=None, fmi: int = 2) -> Path:
    """Pack `model` (an mbfmu model file) into the FMU `out` (default: the model's name
    with .fmu beside it); `out_dir` also writes the unzipped FMU there. Returns `out`.
    `start_values` (a dict parameter or state name -> float) replaces the file's values as
    the FMU's start values (`mbfmu pack --set name=value`: a parameter's every use
    re-evaluated, a state such as `hinge.angle` met exactly at initialization; the
    modelDescription's `start` and an instance's defaults). A model error, an unknown
    name (with a "did you mean" when one is close) or a value the model rejects is raised
    as ArgumentError with the tool's message; what the packed FMU lacks (the tool's
    warnings) is issued as a PackWarning. `fmi=3` packs an FMI 3.0 Co-Simulation FMU
    (with directional and adjoint derivatives) instead of FMI 2.0."""
    model = Path(model)
    if not model.is_file():
        raise FMUNotFoundError(f"model file '{model}' does not exist")
    if fmi not in (2, 3):
        raise ArgumentError(f"fmi={fmi!r}: expected 2 or 3")
    out = Path(out) if out is not None else model.with_suffix(".fmu")
    args = [str(cli()), "pack", str(model), "-o", str(out), "--fmi", str(fmi)]
    if out_dir is not None:
        args += ["--out-dir", str(out_dir)]
    r = run_cli([*args, *set_args(start_values)], "pack")
    for line in r.stderr.splitlines():
        if line.startswith("warning: "):
            warnings.warn(f"{model}: {line.removeprefix('warning: ')}", PackWarning, stacklevel=2)
    return out
