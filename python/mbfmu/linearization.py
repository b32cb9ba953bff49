"""The result of one linearization: ẋ = A x + B u, y = C x + D u about an operating point,
with the names and units of x, u, y, the eigenvalue table, python-control conversion and
files."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: How A, B, C, D were obtained.
DIRECTIONAL = "directional derivatives"
DIFFERENCES = "central differences"


@dataclass(frozen=True)
class EigenRow:
    """One row of the eigenvalue table (one real root or one conjugate pair)."""

    frequency: float
    """Undamped natural frequency |λ| in rad/s."""
    frequency_hz: float
    """|λ| / 2π in Hz."""
    damping: float
    """Damping ratio −Re λ / |λ| (1 for a negative real root, NaN for λ = 0)."""
    real: float
    imag: float
    """Imaginary part, ≥ 0 (one row per pair)."""


def eigen_rows(ev: np.ndarray) -> list[EigenRow]:
    """The table of the CLI (src/linearize/eigen.rs): roots with Im ≥ 0 (|Im| below 1e-12 of
    the largest |λ|, at least 1, counts as real), real roots first, each group by frequency."""
    if ev.size == 0:
        return []
    scale = max(1.0, float(np.max(np.abs(ev))))
    rows = []
    for z in ev:
        if z.imag < -1e-12 * scale:
            continue
        im = 0.0 if abs(z.imag) <= 1e-12 * scale else float(z.imag)
        re = float(z.real) + 0.0
        f = float(np.hypot(re, im))
        rows.append(EigenRow(f, f / (2 * np.pi), -re / f + 0.0 if f > 0 else float("nan"), re, im))
    rows.sort(key=lambda r: (r.imag != 0.0, r.frequency))
    return rows


def format_eigen_table(rows: list[EigenRow]) -> str:
    """The table as text (the CLI's columns plus Hz)."""
    head = f"{'Undmp. Freq.':>14} {'(Hz)':>14} {'Damping Ratio':>14} {'Real':>14} {'Imag':>14}"
    lines = [head] + [
        f"{r.frequency:>14.6e} {r.frequency_hz:>14.6e} {r.damping:>14.6e} {r.real:>14.6e} {r.imag:>14.6e}" for r in rows
    ]
    return "\n".join(lines)


@dataclass
class Linearization:
    """ẋ = A x + B u, y = C x + D u at `time`.

    `states`, `inputs`, `outputs` are the FMU's variable names (x, u, y in order); the
    `*_units` lists hold the FMU's unit strings ('' where none is declared); `x0`, `u0`,
    `y0` are the values at the operating point. `method` says how the matrices were
    obtained: "directional derivatives" (exact, from fmi2GetDirectionalDerivative) or
    "central differences" (the fallback for FMUs without them).
    """

    time: float
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: list[str]
    inputs: list[str]
    outputs: list[str]
    state_units: list[str] = field(default_factory=list)
    input_units: list[str] = field(default_factory=list)
    output_units: list[str] = field(default_factory=list)
    x0: np.ndarray | None = None
    u0: np.ndarray | None = None
    y0: np.ndarray | None = None
    method: str = DIRECTIONAL
    model: str = ""

    def __post_init__(self):
        n, m, p = len(self.states), len(self.inputs), len(self.outputs)
        for name, mat, shape in (
            ("A", self.A, (n, n)),
            ("B", self.B, (n, m)),
            ("C", self.C, (p, n)),
            ("D", self.D, (p, m)),
        ):
            arr = np.asarray(mat, dtype=float).reshape(shape)
            setattr(self, name, arr)
        for attr, k in (("state_units", n), ("input_units", m), ("output_units", p)):
            if not getattr(self, attr):
                setattr(self, attr, [""] * k)

    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of A (complex, as numpy.linalg.eigvals returns them)."""
        return np.linalg.eigvals(self.A) if self.A.size else np.zeros(0, dtype=complex)

    def eigen_table(self) -> list[EigenRow]:
        """The CLI's eigenvalue table: one row per real root or conjugate pair."""
        return eigen_rows(self.eigenvalues())

    def to_control(self, name: str | None = None):
        """A `control.StateSpace` with the state, input and output names set
        (needs the optional dependency python-control: `pip install mbfmu[control]`)."""
        try:
            import control
        except ImportError as e:
            from .errors import MbfmuError

            raise MbfmuError("to_control() needs python-control: pip install 'mbfmu[control]'") from e
        return control.ss(
            self.A,
            self.B,
            self.C,
            self.D,
            states=list(self.states),
            inputs=list(self.inputs),
            outputs=list(self.outputs),
            name=name or self.model or None,
        )

    def save(self, path) -> None:
        """Write to `path`: .npz, .mat (MATLAB v4, scipy.io.loadmat reads it) or .json
        (the layout of `mbfmu linearize --format json`)."""
        from .files import save

        save([self], path)

    def __str__(self) -> str:
        head = (
            f"Linearization of '{self.model}' at t = {self.time:g} ({self.method}): {len(self.states)} states, "
            f"{len(self.inputs)} inputs, {len(self.outputs)} outputs"
        )
        return head + "\n" + format_eigen_table(self.eigen_table())
