"""`linearize(fmu, at)`: one run of an FMU through the times `at`, and A, B, C, D at each.

At a point, [A B; C D] = ∂(ẋ, y)/∂(x, u) comes from fmi2GetDirectionalDerivative with
the FMU's declared structure (structure.py, jacobian.py); an FMU without directional
derivatives is differenced through its Model Exchange interface, with a warning.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from fmpy.fmi3 import FMU3Slave

from .errors import ArgumentError, MbfmuError, NotLinearizableError
from .instance import Instance, Opened, check_start_values, choose_interface, fmi3_flags, is_fmi3
from .jacobian import central_differences, directional
from .linearization import DIFFERENCES, DIRECTIONAL, Linearization
from .structure import Structure, read_structure


class DifferencesWarning(UserWarning):
    """A linearization falls back to central differences (the FMU has no directional derivatives)."""


def start_time_of(md) -> float:
    ex = md.defaultExperiment
    return float(ex.startTime) if ex is not None and ex.startTime is not None else 0.0


def default_tolerance(md) -> float | None:
    ex = md.defaultExperiment
    return float(ex.tolerance) if ex is not None and ex.tolerance is not None else None


def check_times(what: str, at, start: float) -> list[float]:
    """`at` (a number or numbers; None = the start time) as floats, each finite and not before the start."""
    if at is None:
        return [start]
    times = [at] if np.ndim(at) == 0 else list(np.asarray(at, dtype=float).reshape(-1))
    out = []
    for t in times:
        try:
            t = float(t)
        except (TypeError, ValueError) as e:
            raise ArgumentError(f"at: {t!r} is not a time") from e
        if not math.isfinite(t):
            raise ArgumentError(f"at: time {t} is not finite")
        if t < start:
            raise ArgumentError(f"at: time {t:g} is before the start time {start:g} of {what}")
        out.append(t)
    if not out:
        raise ArgumentError("at: no times given")
    return out


def _step_of(md, interface: str, step: float | None, inputs=None, span: float = 1.0) -> float | None:
    """The communication step: `step`; else the FMU's fixed step if it cannot vary it;
    else, with inputs an FMU cannot interpolate, the DefaultExperiment's stepSize (or
    fmpy's automatic interval), so held inputs follow the signal; else None (one step
    to each time and input breakpoint)."""
    if step is not None:
        if not (step > 0 and math.isfinite(step)):
            raise ArgumentError(f"step: {step} must be a positive communication step")
        return float(step)
    if interface != "CoSimulation":
        return None
    cs = md.coSimulation
    ex_step = md.defaultExperiment.stepSize if md.defaultExperiment is not None else None
    if not cs.canHandleVariableCommunicationStepSize:
        if cs.fixedInternalStepSize:
            return float(cs.fixedInternalStepSize)
        if ex_step:
            return float(ex_step)
    if inputs is not None and not cs.canInterpolateInputs:
        from fmpy.util import auto_interval

        return float(ex_step) if ex_step else float(auto_interval(max(span, 1e-9)))
    return None


def linearize_at(inst: Instance, st: Structure, use_dependencies: bool = True) -> Linearization:
    """A, B, C, D of `inst` at its current point."""
    n = len(st.states)
    svr = [v.vr for v in st.states]
    ivr = [v.vr for v in st.inputs]
    ovr = [v.vr for v in st.outputs]
    x0, u0, y0 = inst.get(svr), inst.get(ivr), inst.get(ovr)
    if st.provides_directional_derivative:
        jac = directional(st, inst.directional_derivative, use_dependencies)
        method = DIRECTIONAL
    elif st.interface == "ModelExchange":
        if len(st.states) != inst.md.numberOfContinuousStates:
            raise NotLinearizableError(
                f"FMU '{st.model_name}': {len(st.states)} <Derivatives> but numberOfContinuousStates = "
                f"{inst.md.numberOfContinuousStates}"
            )

        def f(k: np.ndarray) -> np.ndarray:
            inst.set_states(k[:n])
            inst.set(ivr, k[n:])
            return np.concatenate([inst.get_derivatives(n), inst.get(ovr)])

        jac = central_differences(st, f, np.concatenate([inst.get_states(n), u0]))
        method = DIFFERENCES
    else:
        raise NotLinearizableError(
            f"FMU '{st.model_name}' provides no directional derivatives and no Model Exchange interface: "
            "the states of a Co-Simulation FMU cannot be set, so it cannot be differenced either"
        )
    nd = len(st.derivatives)
    return Linearization(
        time=inst.time,
        A=jac[:nd, :n],
        B=jac[:nd, n:],
        C=jac[nd:, :n],
        D=jac[nd:, n:],
        states=[v.name for v in st.states],
        inputs=[v.name for v in st.inputs],
        outputs=[v.name for v in st.outputs],
        state_units=[v.unit or "" for v in st.states],
        input_units=[v.unit or "" for v in st.inputs],
        output_units=[v.unit or "" for v in st.outputs],
        x0=x0,
        u0=u0,
        y0=y0,
        method=method,
        model=st.model_name,
    )


def _progress(items: Iterable, enabled: bool, total: int, desc: str):
    if not enabled:
        return items
    try:
        from tqdm.auto import tqdm
    except ImportError as e:
        raise MbfmuError("progress=True needs tqdm: pip install 'mbfmu[progress]'") from e
    return tqdm(items, total=total, desc=desc)


def _warn_differences(st: Structure) -> None:
    if not st.provides_directional_derivative:
        warnings.warn(
            f"FMU '{st.model_name}' provides no directional derivatives: A, B, C, D by central differences "
            "(about 1e-8 relative; lin.method says so)",
            DifferencesWarning,
            stacklevel=3,
        )


def linearize_opened(
    op: Opened,
    at=None,
    start_values=None,
    inputs=None,
    tolerance=None,
    progress=False,
    step=None,
    interface=None,
    use_dependencies=True,
) -> list[Linearization]:
    """`linearize` on an FMU already opened (extracted) — what sweeps reuse per point."""
    md = op.md
    interface = choose_interface(md, interface)
    st = read_structure(md, interface)
    start = start_time_of(md)
    times = check_times(f"FMU '{md.modelName}'", at, start)
    check_start_values(md, dict(start_values or {}))
    step = _step_of(md, interface, step, inputs, max(times) - start)
    tol = tolerance if tolerance is not None else default_tolerance(md)
    if tol is not None and not (tol > 0 and math.isfinite(tol)):
        raise ArgumentError(f"tolerance: {tol} must be positive")
    _warn_differences(st)
    order = sorted(range(len(times)), key=lambda i: times[i])
    out: list[Linearization | None] = [None] * len(times)
    with Instance(op.unzipdir, md, interface, tol) as inst:
        inst.initialize(start, start_values, inputs)
        for i in _progress(order, progress, len(order), f"linearizing {md.modelName}"):
            inst.advance(times[i], step)
            out[i] = linearize_at(inst, st, use_dependencies)
    return out  # type: ignore[return-value]


def _live_time(fmu, md) -> float | None:
    try:
        if isinstance(fmu, FMU3Slave):  # FMI 3: the independent variable
            vr = next(v.valueReference for v in md.modelVariables if v.causality == "independent")
            return float(fmu.getFloat64([vr])[0])
        return float(fmu.getRealStatus(2))  # fmi2LastSuccessfulTime
    except Exception:
        return None


def linearize_instance(fmu, at=None, step=None, use_dependencies=True) -> list[Linearization]:
    """Linearize a host's fmpy instance where it stands (at=None) or, for Co-Simulation,
    after stepping it on to each time in `at`. The instance stays the host's."""
    from fmpy import read_model_description

    md = read_model_description(fmu.unzipDirectory, validate=False)
    if is_fmi3(md):
        fmi3_flags(md, Path(fmu.unzipDirectory) / "modelDescription.xml")
    inst = Instance.attach(fmu, md, math.nan)
    st = read_structure(md, inst.interface)
    _warn_differences(st)
    now = _live_time(fmu, md) if inst.interface == "CoSimulation" else None
    if at is None:
        if now is not None:
            inst.time = inst.start_time = now
        return [linearize_at(inst, st, use_dependencies)]
    times = check_times(f"FMU '{md.modelName}'", at, -math.inf)
    if inst.interface == "ModelExchange":
        if len(times) != 1:
            raise ArgumentError("a Model Exchange instance is linearized where it stands: give at=None or one time")
        inst.time = times[0]
        return [linearize_at(inst, st, use_dependencies)]
    if now is None:
        raise ArgumentError(
            f"FMU '{md.modelName}' does not report its time (fmi2GetRealStatus(fmi2LastSuccessfulTime)): "
            "call linearize(instance) with at=None to linearize where it stands"
        )
    inst.time = inst.start_time = now
    for t in times:
        if t < inst.time - 1e-12 * max(1.0, abs(t)):
            raise ArgumentError(f"at: time {t:g} is before the instance's current time {inst.time:g}")
    order = sorted(range(len(times)), key=lambda i: times[i])
    out: list[Linearization | None] = [None] * len(times)
    for i in order:
        if times[i] > inst.time:
            inst.advance(times[i], _step_of(md, "CoSimulation", step))
        out[i] = linearize_at(inst, st, use_dependencies)
    return out  # type: ignore[return-value]


def linearize(
    fmu,
    at=None,
    start_values=None,
    inputs=None,
    tolerance=None,
    progress=False,
    *,
    step=None,
    interface=None,
    use_dependencies=True,
) -> list[Linearization]:
    """Simulate `fmu` once through the times `at` and return its linearization at each.

    fmu: path of an FMI 2.0 FMU (zip or extracted directory), Co-Simulation or Model
        Exchange, or of an FMI 3.0 Co-Simulation FMU; or an instantiated fmpy
        FMU2Slave/FMU2Model/FMU3Slave at a communication point
        (then only `at`, `step`, `use_dependencies` apply; at=None linearizes where it stands).
    at: a time or times (any order; results come back in that order); None = start time.
    start_values: {name: value} for parameters and start values, as fmpy.simulate_fmu.
    inputs: a structured array (first field time, then one field per input), as
        fmpy.simulate_fmu's `input`; linear interpolation between its rows.
    tolerance: the FMU's integration tolerance (default: the DefaultExperiment's).
    progress: show a tqdm progress bar over the times.
    step: communication step (default: straight to each time and input breakpoint, or
        the FMU's fixed step if it cannot vary it).
    interface: 'CoSimulation' or 'ModelExchange' (default: the one with directional
        derivatives, Co-Simulation first; else Model Exchange, differenced).
    use_dependencies: trust the declared ModelStructure dependencies to skip zeros and
        to seed columns in groups (set False for an FMU whose declarations are wrong).
    """
    from fmpy.fmi2 import _FMU2

    if isinstance(fmu, _FMU2 | FMU3Slave):
        if start_values or inputs is not None or tolerance is not None:
            raise ArgumentError(
                "start_values, inputs and tolerance cannot be given for an instance that is already "
                "initialized; set them on the instance"
            )
        return linearize_instance(fmu, at, step, use_dependencies)
    with Opened(fmu) as op:
        return linearize_opened(op, at, start_values, inputs, tolerance, progress, step, interface, use_dependencies)
