"""One FMU instance (FMI 2.0; FMI 3.0 Co-Simulation) driven through time: open (zip or
directory), instantiate with a logger whose messages go into errors, initialize with start values and fmpy-style input
signals, advance to a time (Co-Simulation: doStep; Model Exchange: CVode with events),
and read values and directional derivatives at the current point.

Failed FMI calls become FMUCallError naming the function, the time and the FMU's last
log messages; the instance is freed by `close()` (or the context manager) in every case.
"""

from __future__ import annotations

import ctypes
import itertools
import math
import os
import shutil
import threading
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import (
    FMU2Model,
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.fmi3 import FMU3Slave

from .errors import ArgumentError, FMUCallError, FMUNotFoundError, MbfmuError

# The step bound of mbfmu FMUs, and the budget this package gives one step to a time.
MAX_STEPS_VARIABLE = "solver.maxSteps"
BATCH_MAX_STEPS = 1_000_000

# --- log capture --------------------------------------------------------------------
# fmpy's native proxy (fmpy.logging.addLoggerProxy) formats the variadic message and calls
# one Python function; that function is process-wide, so one dispatcher routes messages
# to the instance they name.
_LOGS: dict[str, list[str]] = {}
_LOG_LOCK = threading.Lock()
_NAMES = itertools.count()
_STATUS = ["OK", "Warning", "Discard", "Error", "Fatal", "Pending"]


def _dispatch(env, name, status, category, message):
    key = name.decode("utf-8", "replace") if name else ""
    text = message.decode("utf-8", "replace") if message else ""
    cat = category.decode("utf-8", "replace") if category else ""
    with _LOG_LOCK:
        log = _LOGS.get(key)
        if log is not None:
            log.append(f"[{_STATUS[status] if 0 <= status < len(_STATUS) else status}] {cat}: {text}")
            del log[:-50]


_DISPATCH = fmi2CallbackLoggerTYPE(_dispatch)
_libc = ctypes.CDLL(None)
_calloc = fmi2CallbackAllocateMemoryTYPE(("calloc", _libc))
_free = fmi2CallbackFreeMemoryTYPE(("free", _libc))


def _callbacks() -> fmi2CallbackFunctions:
    cb = fmi2CallbackFunctions()
    cb.logger = _DISPATCH
    cb.allocateMemory = _calloc
    cb.freeMemory = _free
    try:
        from fmpy.logging import addLoggerProxy

        addLoggerProxy(ctypes.byref(cb))
    except Exception:  # pragma: no cover - the proxy ships with fmpy's wheels
        pass
    return cb


class _Slopes:
    """Slopes of the continuous real inputs of an fmpy input array, segment ahead of t
    (the later of repeated times; 0 before the first and after the last row)."""

    def __init__(self, md, signals):
        names = signals.dtype.names
        self.t = np.asarray(signals[names[0]], dtype=float)
        vars_ = [
            v
            for v in md.modelVariables
            if v.causality == "input" and v.type == "Real" and v.variability == "continuous" and v.name in names
        ]
        self.vrs = [v.valueReference for v in vars_]
        self.cols = [np.asarray(signals[v.name], dtype=float) for v in vars_]

    def at(self, time: float) -> list[float]:
        k = int(np.searchsorted(self.t, time, side="right")) - 1
        if k < 0 or k + 1 >= len(self.t) or self.t[k + 1] <= self.t[k]:
            return [0.0] * len(self.vrs)
        dt = self.t[k + 1] - self.t[k]
        return [float((c[k + 1] - c[k]) / dt) for c in self.cols]


# --- opening ------------------------------------------------------------------------


class Opened:
    """An FMU on disk: its unzip directory (a temporary one for a zip) and description."""

    def __init__(self, path: str | os.PathLike):
        p = Path(path)
        if not p.exists():
            raise FMUNotFoundError(f"FMU '{p}' does not exist")
        self.path = p
        self._tmp = None
        try:
            if p.is_dir():
                self.unzipdir = str(p)
            else:
                self._tmp = extract(str(p))
                self.unzipdir = self._tmp
            self.md = read_model_description(self.unzipdir, validate=False)
            if is_fmi3(self.md):
                fmi3_flags(self.md, Path(self.unzipdir) / "modelDescription.xml")
        except MbfmuError:
            raise
        except Exception as e:
            self.close()
            raise MbfmuError(f"FMU '{p}' cannot be read: {e}") from e

    def close(self):
        if self._tmp is not None:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def is_fmi3(md) -> bool:
    """Whether `md` describes an FMI 3.0 FMU."""
    return str(md.fmiVersion).startswith("3.")


def fmi3_flags(md, xml: Path) -> None:
    """fmpy 0.3.x reads FMI 3's `providesDirectionalDerivatives` under its FMI 2 name,
    `providesDirectionalDerivative`, so it reports False for every FMI 3 FMU: take the
    flag from the file."""
    import xml.etree.ElementTree as ET

    root = ET.parse(xml).getroot()
    for tag, info in (("CoSimulation", md.coSimulation), ("ModelExchange", md.modelExchange)):
        node = root.find(tag)
        if info is not None and node is not None:
            info.providesDirectionalDerivative = node.get("providesDirectionalDerivatives") == "true"


def choose_interface(md, interface: str | None = None) -> str:
    """'CoSimulation' or 'ModelExchange': the requested one, else the one that provides
    directional derivatives (Co-Simulation first), else Co-Simulation if it is all there is."""
    have = {"CoSimulation": md.coSimulation, "ModelExchange": md.modelExchange}
    if interface is not None:
        if interface not in have:
            raise ArgumentError(f"interface '{interface}': expected 'CoSimulation' or 'ModelExchange'")
        if have[interface] is None:
            raise ArgumentError(f"FMU '{md.modelName}' has no {interface} interface")
        return interface
    for kind in ("CoSimulation", "ModelExchange"):
        if have[kind] is not None and have[kind].providesDirectionalDerivative:
            return kind
    # No directional derivatives: Model Exchange can be differenced legally
    # (fmi2SetContinuousStates); Co-Simulation states cannot be set.
    for kind in ("ModelExchange", "CoSimulation"):
        if have[kind] is not None:
            return kind
    raise MbfmuError(f"FMU '{md.modelName}' has neither a Co-Simulation nor a Model Exchange interface")


def settable_in_instantiated(v) -> bool:
    return v.causality == "input" or (v.variability != "constant" and v.initial in {"approx", "exact"})


def settable_in_initialization(v) -> bool:
    return (
        v.causality == "input"
        or (v.causality != "parameter" and v.variability == "tunable")
        or (v.variability != "constant" and v.initial == "exact")
    )


def check_start_values(md, start_values: dict) -> None:
    """Every name must be a variable that can be given a start value."""
    by_name = {v.name: v for v in md.modelVariables}
    for name in start_values:
        v = by_name.get(name)
        if v is None:
            import difflib

            close = difflib.get_close_matches(name, list(by_name), n=3)
            hint = f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""
            raise ArgumentError(f"FMU '{md.modelName}' has no variable '{name}'{hint}")
        if not (settable_in_instantiated(v) or settable_in_initialization(v)):
            raise ArgumentError(
                f"FMU '{md.modelName}': variable '{name}' (causality {v.causality}, variability {v.variability}, "
                f"initial {v.initial}) cannot be given a start value"
            )


# --- the instance -------------------------------------------------------------------


class Instance:
    """An instantiated, initialized FMU interface at a current time."""

    def __init__(self, unzipdir: str, md, interface: str, tolerance: float | None = None):
        self.md = md
        self.interface = interface
        self.name = f"mbfmu{next(_NAMES)}"
        with _LOG_LOCK:
            _LOGS[self.name] = []
        self.fmi3 = is_fmi3(md)
        if self.fmi3 and interface != "CoSimulation":
            raise ArgumentError(
                f"FMU '{md.modelName}': the mbfmu package drives FMI 3.0 FMUs through Co-Simulation only "
                "(their Model Exchange interface works in FMI hosts, e.g. fmpy's simulate_fmu)"
            )
        cls = FMU3Slave if self.fmi3 else FMU2Slave if interface == "CoSimulation" else FMU2Model
        info = md.coSimulation if interface == "CoSimulation" else md.modelExchange
        self.time = math.nan
        self.fmu = self._call(
            "loading the FMU's shared library",
            cls,
            guid=md.guid,
            unzipDirectory=unzipdir,
            modelIdentifier=info.modelIdentifier,
            instanceName=self.name,
        )
        self._callbacks = _callbacks()
        self.tolerance = tolerance
        self._input = None
        self._solver = None
        self._next_event = math.inf
        self._alive = False
        if self.fmi3:
            self._call("fmi3InstantiateCoSimulation", lambda: self.fmu.instantiate(logMessage=self._log3))
        else:
            self._call("fmi2Instantiate", lambda: self.fmu.instantiate(callbacks=self._callbacks, loggingOn=False))
        self._alive = True

    def _log3(self, env, status, category, message) -> None:
        """The FMI 3 logMessage callback (it names no instance: one closure per instance)."""
        _dispatch(env, self.name.encode(), status, category, message)

    @classmethod
    def attach(cls, fmu, md, time: float) -> Instance:
        """Wrap a host's fmpy instance (already initialized, at `time`); `close()` leaves it alive."""
        self = cls.__new__(cls)
        self.md = md
        self.interface = "ModelExchange" if isinstance(fmu, FMU2Model) else "CoSimulation"
        self.fmi3 = isinstance(fmu, FMU3Slave)
        self.name = getattr(fmu, "instanceName", "host instance")
        self.fmu = fmu
        self.time = self.start_time = float(time)
        self.tolerance = None
        self._input = None
        self._slopes = None
        self._solver = None
        self._next_event = math.inf
        self._alive = False  # not ours to terminate or free
        return self

    # -- errors --

    def log(self) -> list[str]:
        """The FMU's messages so far (the last 50)."""
        with _LOG_LOCK:
            return list(_LOGS.get(self.name, []))

    def _call(self, what: str, fn, *args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except Exception as e:  # FMICallException and whatever a host's FMU raises
            if isinstance(e, MbfmuError):
                raise
            log = self.log()
            at = "" if math.isnan(self.time) else f" at t = {self.time:g}"
            tail = ("; the FMU logged:\n  " + "\n  ".join(log[-8:])) if log else ""
            raise FMUCallError(f"FMU '{self.md.modelName}': {what} failed{at}: {e}{tail}") from e

    # -- set-up --

    def initialize(
        self, start_time: float, start_values: dict | None = None, inputs=None, stop_time: float | None = None
    ) -> None:
        """setupExperiment, start values, inputs at start_time, initialization mode."""
        from fmpy.simulation import Input, apply_start_values

        sv = dict(start_values or {})
        check_start_values(self.md, sv)
        fmu = self.fmu
        cs = self.interface == "CoSimulation"
        if cs and MAX_STEPS_VARIABLE not in sv and any(v.name == MAX_STEPS_VARIABLE for v in self.md.modelVariables):
            # An mbfmu FMU bounds one fmi2DoStep (solver.maxSteps, default 10 000); this
            # package goes to each time asked in one step, so it gives that step the budget
            # its Model Exchange path gives CVode (and `mbfmu linearize` its engine).
            sv[MAX_STEPS_VARIABLE] = BATCH_MAX_STEPS
        self.time = start_time
        self.start_time = start_time
        # The experiment: FMI 2 sets it first; FMI 3 passes it on entering initialization.
        if not self.fmi3:
            tol = self.tolerance if cs else None
            self._call(
                "fmi2SetupExperiment",
                lambda: fmu.setupExperiment(tolerance=tol, startTime=start_time, stopTime=stop_time),
            )
        sv = self._call("setting start values", lambda: apply_start_values(fmu, self.md, sv, settable_in_instantiated))
        if self.fmi3:
            self._call(
                "fmi3EnterInitializationMode",
                lambda: fmu.enterInitializationMode(tolerance=self.tolerance, startTime=start_time, stopTime=stop_time),
            )
        else:
            self._call("fmi2EnterInitializationMode", fmu.enterInitializationMode)
        sv = self._call(
            "setting start values", lambda: apply_start_values(fmu, self.md, sv, settable_in_initialization)
        )
        if sv:
            raise ArgumentError(f"FMU '{self.md.modelName}': start values not set: {', '.join(sv)}")
        # Slopes are set here, not by fmpy's Input(set_input_derivatives=True), whose buffer
        # holds exactly 9 inputs (fmpy 0.3.x).
        self._slopes = None
        if cs and not self.fmi3 and bool(self.md.coSimulation.canInterpolateInputs) and inputs is not None:
            self._slopes = _Slopes(self.md, inputs)
        self._input = self._call("reading inputs", lambda: Input(fmu, self.md, inputs))
        self._apply_inputs()
        self._call("fmi2ExitInitializationMode", fmu.exitInitializationMode)
        if not cs:
            self._me_event_iteration()
            self._call("fmi2EnterContinuousTimeMode", fmu.enterContinuousTimeMode)
            self._start_solver(start_time)

    def _me_event_iteration(self):
        while True:
            need, terminate, _, _, defined, t_next = self._call("fmi2NewDiscreteStates", self.fmu.newDiscreteStates)
            if terminate:
                raise FMUCallError(f"FMU '{self.md.modelName}' asked to terminate at t = {self.time:g}")
            if not need:
                break
        self._next_event = t_next if defined else math.inf

    def _start_solver(self, t: float):
        from fmpy.sundials import CVodeSolver

        md = self.md
        fmu = self.fmu
        self._solver = CVodeSolver(
            nx=md.numberOfContinuousStates,
            nz=md.numberOfEventIndicators,
            get_x=fmu.getContinuousStates,
            set_x=fmu.setContinuousStates,
            get_dx=fmu.getDerivatives,
            get_z=fmu.getEventIndicators,
            get_nominals=fmu.getNominalsOfContinuousStates,
            set_time=self._set_time_and_inputs,
            input=self._input,
            startTime=t,
            relativeTolerance=self.tolerance or 1e-8,
            maxNumSteps=1_000_000,
        )

    def _set_time_and_inputs(self, t: float) -> None:
        # fmpy's CVode right-hand side sets only the time: continuous inputs follow here.
        self.fmu.setTime(t)
        if self._input is not None:
            self._input.apply(t, discrete=False)

    # -- time --

    def advance(self, t: float, step: float | None = None) -> None:
        """Simulate from the current time to t (communication points at the inputs'
        breakpoints, every `step` if given, and t), then apply the inputs at t."""
        if t < self.time:
            raise ArgumentError(f"cannot go back from t = {self.time:g} to t = {t:g}")
        points = self._points(t, step)
        for tn in points:
            if self.interface == "CoSimulation":
                self._apply_inputs()
                t0 = self.time
                self._call("fmi2DoStep", self.fmu.doStep, currentCommunicationPoint=t0, communicationStepSize=tn - t0)
                self.time = tn
            else:
                self._integrate(tn)
        self._apply_inputs()

    def _apply_inputs(self) -> None:
        if self._input is not None:
            # after_event: at a repeated time the later row holds from now on (as the slopes).
            self._call("setting inputs", lambda: self._input.apply(self.time, after_event=True))
        if getattr(self, "_slopes", None) is not None and self._slopes.vrs:
            slopes = self._slopes.at(self.time)
            self._call(
                "fmi2SetRealInputDerivatives",
                self.fmu.setRealInputDerivatives,
                self._slopes.vrs,
                [1] * len(slopes),
                slopes,
            )

    def _points(self, t: float, step: float | None) -> list[float]:
        """Communication points in (time, t]: the grid start + k*step, the input table's
        times (so piecewise-linear inputs are followed exactly), and t."""
        pts = {t}
        if step is not None:
            k = math.floor((self.time - self.start_time) / step + 1e-9) + 1
            while self.start_time + k * step < t * (1 - 1e-12):
                pts.add(self.start_time + k * step)
                k += 1
        if self._input is not None and self._input.t is not None:
            pts.update(float(x) for x in np.unique(self._input.t) if self.time < x < t)
        return sorted(p for p in pts if p > self.time)

    def _integrate(self, t_end: float) -> None:
        fmu, solver = self.fmu, self._solver
        while self.time < t_end:
            t_next = min(t_end, self._next_event)
            state_event, _, time = self._call("integrating (CVode)", solver.step, self.time, t_next)
            self.time = time
            self._call("fmi2SetTime", fmu.setTime, time)
            if self._input is not None:
                self._input.apply(time, discrete=False)
            step_event = False
            if self.md.modelExchange.needsCompletedIntegratorStep:
                step_event, terminate = self._call("fmi2CompletedIntegratorStep", fmu.completedIntegratorStep)
                if terminate:
                    raise FMUCallError(f"FMU '{self.md.modelName}' asked to terminate at t = {time:g}")
            time_event = time >= self._next_event
            if state_event or step_event or time_event:
                self._call("fmi2EnterEventMode", fmu.enterEventMode)
                self._me_event_iteration()
                self._call("fmi2EnterContinuousTimeMode", fmu.enterContinuousTimeMode)
                solver.reset(time)
            if time >= t_end or math.isclose(time, t_end, rel_tol=1e-14, abs_tol=1e-14):
                self.time = t_end
                break

    # -- values --

    def get(self, vrs) -> np.ndarray:
        vrs = list(vrs)
        if not vrs:
            return np.zeros(0)
        if self.fmi3:
            return np.array(self._call("fmi3GetFloat64", lambda: self.fmu.getFloat64(vrs)), dtype=float)
        return np.array(self._call("fmi2GetReal", lambda: self.fmu.getReal(vrs)), dtype=float)

    def set(self, vrs, values) -> None:
        vrs = list(vrs)
        if vrs and self.fmi3:
            self._call("fmi3SetFloat64", lambda: self.fmu.setFloat64(vrs, [float(v) for v in values]))
        elif vrs:
            self._call("fmi2SetReal", lambda: self.fmu.setReal(vrs, [float(v) for v in values]))

    def directional_derivative(self, unknowns, knowns, seeds) -> list[float]:
        if self.fmi3:
            return self._call(
                "fmi3GetDirectionalDerivative",
                lambda: self.fmu.getDirectionalDerivative(list(unknowns), list(knowns), list(seeds)),
            )
        return self._call(
            "fmi2GetDirectionalDerivative",
            lambda: self.fmu.getDirectionalDerivative(list(unknowns), list(knowns), list(seeds)),
        )

    def set_states(self, x: np.ndarray) -> None:
        arr = (ctypes.c_double * len(x))(*x)
        self._call("fmi2SetContinuousStates", lambda: self.fmu.setContinuousStates(arr, len(x)))

    def get_states(self, n: int) -> np.ndarray:
        arr = (ctypes.c_double * n)()
        self._call("fmi2GetContinuousStates", lambda: self.fmu.getContinuousStates(arr, n))
        return np.array(arr[:], dtype=float)

    def get_derivatives(self, n: int) -> np.ndarray:
        arr = (ctypes.c_double * n)()
        self._call("fmi2GetDerivatives", lambda: self.fmu.getDerivatives(arr, n))
        return np.array(arr[:], dtype=float)

    # -- end --

    def close(self) -> None:
        if self._alive:
            self._alive = False
            self._solver = None
            try:
                self.fmu.terminate()
            except Exception:
                pass
            try:
                self.fmu.freeInstance()
            except Exception:
                pass
        with _LOG_LOCK:
            _LOGS.pop(self.name, None)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
