"""`eigenvalues(model, at, modes=K, shift=σ)`: the eigenvalues of a mechanism at operating
points — all of them, or only the K nearest a shift. For an mbfmu model file the
`mbfmu linearize` tool computes them: with `modes` by shift-invert Arnoldi on the sparse
linearized equations, never forming A (for models of thousands of bodies; at equilibria
only). For an FMU, A comes from its directional derivatives (as `linearize`) and its
eigenvalues from a dense eigensolver, of which the K nearest σ are kept."""

from __future__ import annotations

import json
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ArgumentError, FMUNotFoundError
from .linearization import EigenRow, eigen_rows, format_eigen_table
from .linearize_fmu import linearize
from .pack import cli, run_cli, set_args

#: How the eigenvalues were found.
SHIFT_INVERT = "shift-invert Arnoldi on the sparse linearized equations (mbfmu linearize --modes)"
FULL_MODEL = "all eigenvalues of A (mbfmu linearize)"
FULL_FMU = "eigenvalues of the FMU's A (directional derivatives, dense eigensolver)"


@dataclass
class Spectrum:
    """Eigenvalues of the linearized system at `time` (complex, nearest `shift` first when
    `shift` is not None), and how they were found (`route`)."""

    time: float
    eigenvalues: np.ndarray
    route: str
    shift: complex | None = None

    def eigen_table(self) -> list[EigenRow]:
        """The CLI's table: one row per real root or conjugate pair. For a complex shift
        each eigenvalue stands for its pair and is shown once, with Im ≥ 0."""
        ev = self.eigenvalues
        if self.shift is not None and self.shift.imag != 0.0:
            shown: list[complex] = []
            for z in np.where(ev.imag < 0, ev.conj(), ev):
                if not any(abs(w - z) <= 1e-10 * abs(z) for w in shown):
                    shown.append(complex(z))
            ev = np.array(shown, dtype=complex)
        return eigen_rows(ev)

    def __str__(self) -> str:
        z = self.shift
        near = "" if z is None else f" nearest {z.real:g}" + (f"{z.imag:+g}i" if z.imag else "")
        head = f"t = {self.time}: {len(self.eigenvalues)} eigenvalues{near} ({self.route})"
        return head + "\n" + format_eigen_table(self.eigen_table())


def _shift_text(z: complex) -> str:
    """`--shift` text the tool reads back exactly: `2.0` or `0.0+62.8i`."""
    return repr(z.real) if z.imag == 0.0 else f"{z.real!r}{'+' if z.imag >= 0 else ''}{z.imag!r}i"


def _times(at) -> list[float] | None:
    if at is None:
        return None
    times = [float(t) for t in np.atleast_1d(np.asarray(at, dtype=float))]
    if not times:
        raise ArgumentError("at: no times given")
    return times


def nearest(ev: np.ndarray, k: int, shift: complex) -> np.ndarray:
    """The k of `ev` nearest `shift`, nearest first; for a real shift a conjugate pair cut
    in two by the k-th is completed (as the tool does)."""
    order = np.argsort(np.abs(ev - shift), kind="stable")
    take = min(k, ev.size)
    if shift.imag == 0.0 and 0 < take < ev.size:
        last, nxt = ev[order[take - 1]], ev[order[take]]
        scale = max(1.0, float(np.max(np.abs(ev))))
        if last.imag != 0.0 and abs(nxt - last.conjugate()) <= 1e-10 * scale:
            take += 1
    return ev[order[:take]]


def _from_model(model: Path, times, modes, shift, start_values, static, tolerance) -> list[Spectrum]:
    args = [str(cli()), "linearize", str(model), "--format", "json"]
    if times is not None:
        args.append("--at=" + ",".join(repr(t) for t in times))
    if modes is not None:
        args += ["--modes", str(modes), "--shift", _shift_text(shift)]
    if static:
        args.append("--static")
    if tolerance is not None:
        args += ["--tol", repr(float(tolerance))]
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "eig.json"
        run_cli([*args, *set_args(start_values), "-o", str(out)], "linearize")
        items = json.loads(out.read_text())
    result = []
    for it in items:
        ev = np.array([complex(re, im) for re, im in it["eigenvalues"]], dtype=complex)
        if modes is None:
            result.append(Spectrum(float(it["time"]), ev, FULL_MODEL))
        else:
            used = complex(*it["shift"])
            result.append(Spectrum(float(it["time"]), ev, SHIFT_INVERT, used))
    if times is None:
        return result
    # The tool answers in time order: give them back in the order asked.
    order = np.argsort(times, kind="stable")
    back: list[Spectrum] = [None] * len(times)  # type: ignore[list-item]
    for spectrum, i in zip(result, order, strict=True):
        back[i] = spectrum
    return back


def eigenvalues(
    model, at=None, modes: int | None = None, shift: complex = 0.0, start_values=None, *, static=False, tolerance=None
) -> list[Spectrum]:
    """Eigenvalues of `model` linearized at the times `at` (default: its start), one
    Spectrum per time, in the order asked.

    model: an mbfmu model file (`.xml`): `mbfmu linearize` computes them; or an FMU (path):
        A from its directional derivatives (`linearize`), then all its eigenvalues.
    modes: only the K eigenvalues nearest `shift`. For a model file by shift-invert
        Arnoldi on the sparse linearized equations, without forming A (at equilibria only:
        elsewhere ArgumentError says so; `static=True` starts at rest); for an FMU the K
        nearest of all.
    shift: real (default 0: the lowest |λ|) or complex (1j * ω: the modes nearest the
        frequency ω rad/s).
    start_values: {name: value} of parameters and states, as for `pack` and `linearize`.
    static: start from the static equilibrium (`mbfmu linearize --static`; model files).
    tolerance: the integration tolerance (default: the model's or FMU's).
    """
    times = _times(at)
    if modes is not None and (isinstance(modes, bool) or not isinstance(modes, (int, np.integer)) or modes < 1):
        raise ArgumentError(f"modes={modes!r}: expected a positive number of eigenvalues")
    try:
        shift = complex(shift)
    except (TypeError, ValueError):
        raise ArgumentError(f"shift={shift!r} is not a number") from None
    if not np.isfinite(shift.real) or not np.isfinite(shift.imag):
        raise ArgumentError(f"shift={shift!r}: expected a finite number")
    path = Path(model)
    if not path.exists():
        raise FMUNotFoundError(f"'{path}' does not exist")
    if path.suffix.lower() == ".xml":
        return _from_model(path, times, modes, shift, start_values, static, tolerance)
    if static:
        raise ArgumentError("static=True applies to model files; an FMU starts where its start values put it")
    lins = linearize(path, at=times, start_values=start_values, tolerance=tolerance)
    out = []
    for lin in lins:
        ev = lin.eigenvalues()
        if modes is None:
            out.append(Spectrum(lin.time, ev, FULL_FMU))
        else:
            out.append(Spectrum(lin.time, nearest(ev, int(modes), shift), FULL_FMU, shift))
    return out
