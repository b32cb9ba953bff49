"""`sweep(fmu, parameter, values, at)`: the linearization for each value of a parameter
(or start value), serially or on a Dask cluster, and the root-locus style picture of
Meijaard et al. 2007, Fig. 3 (real and imaginary parts of the eigenvalues against the
parameter)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ArgumentError
from .instance import Opened, check_start_values
from .linearization import Linearization
from .linearize_fmu import _progress, linearize_opened


@dataclass
class Sweep:
    """The result of a sweep: `linearizations[i][k]` is the linearization for `values[i]`
    at time `times[k]`."""

    parameter: str
    values: np.ndarray
    times: list[float]
    linearizations: list[list[Linearization]]
    unit: str = ""

    def eigenvalues(self, time_index: int = 0) -> np.ndarray:
        """Eigenvalues per value, shape (len(values), n), each row sorted by (real, imag)."""
        rows = [np.sort_complex(lins[time_index].eigenvalues()) for lins in self.linearizations]
        return np.array(rows)

    def plot(self, path=None, time_index: int = 0, ax=None, title: str | None = None):
        """Real parts (solid) and imaginary parts ≥ 0 (dashed) of the eigenvalues against the
        parameter; writes a PNG to `path` when given. Returns the matplotlib Axes."""
        try:
            import matplotlib

            if ax is None:
                matplotlib.use("Agg", force=False)
            import matplotlib.pyplot as plt
        except ImportError as e:
            from .errors import MbfmuError

            raise MbfmuError("Sweep.plot needs matplotlib: pip install 'mbfmu[plot]'") from e
        ev = self.eigenvalues(time_index)
        fig = None
        if ax is None:
            fig, ax = plt.subplots(figsize=(7, 4.5))
        x = self.values
        # One line per sorted eigenvalue slot; eigenvalues that cross swap slots, which the
        # markers keep readable.
        for j in range(ev.shape[1]):
            ax.plot(
                x,
                ev[:, j].real,
                "-",
                color="C0",
                marker=".",
                markersize=3,
                linewidth=1,
                label="Re λ" if j == 0 else None,
            )
        for j in range(ev.shape[1]):
            im = np.where(ev[:, j].imag > 0, ev[:, j].imag, np.nan)
            ax.plot(x, im, "--", color="C1", marker=".", markersize=3, linewidth=1, label="Im λ" if j == 0 else None)
        ax.axhline(0.0, color="k", linewidth=0.5)
        unit = f" ({self.unit})" if self.unit else ""
        ax.set_xlabel(f"{self.parameter}{unit}")
        ax.set_ylabel("eigenvalue λ (1/s)")
        model = self.linearizations[0][time_index].model if self.linearizations else ""
        ax.set_title(title or f"{model}: eigenvalues against {self.parameter} at t = {self.times[time_index]:g}")
        ax.legend(loc="best")
        ax.grid(True, linewidth=0.3)
        if path is not None:
            (fig or ax.figure).savefig(Path(path), dpi=120, bbox_inches="tight")
        return ax


def _point(fmu, at, start_values, inputs, tolerance, kw) -> list[Linearization]:
    """One sweep point on a fresh instance (what a Dask worker runs)."""
    with Opened(fmu) as op:
        return linearize_opened(op, at, start_values, inputs, tolerance, **kw)


def sweep(
    fmu,
    parameter: str,
    values,
    at=None,
    start_values=None,
    inputs=None,
    tolerance=None,
    progress=False,
    client=None,
    **kw,
) -> Sweep:
    """Linearize `fmu` at the times `at` for each value of `parameter` (a parameter or
    any variable that takes a start value); the other arguments as for `linearize`.

    client: a `dask.distributed.Client`; the points then run on its workers (each opens the
    FMU itself, so the FMU path must be readable there). Results are identical to serial.
    """
    values = np.asarray(values, dtype=float).reshape(-1)
    if values.size == 0:
        raise ArgumentError("values: no parameter values given")
    base = dict(start_values or {})
    with Opened(fmu) as op:
        check_start_values(op.md, {**base, parameter: float(values[0])})
        var = next(v for v in op.md.modelVariables if v.name == parameter)
        unit = var.unit or getattr(getattr(var, "declaredType", None), "unit", None) or ""
        points = [{**base, parameter: float(v)} for v in values]
        if client is None:
            results = [
                linearize_opened(op, at, sv, inputs, tolerance, **kw)
                for sv in _progress(points, progress, len(points), f"sweep {parameter}")
            ]
        else:
            path = str(Path(fmu).resolve())
            futures = [client.submit(_point, path, at, sv, inputs, tolerance, kw, pure=False) for sv in points]
            if progress:
                from dask.distributed import as_completed

                for _ in _progress(as_completed(futures), True, len(futures), f"sweep {parameter}"):
                    pass
            results = client.gather(futures)
    times = [lin.time for lin in results[0]]
    return Sweep(parameter, values, times, results, unit)
