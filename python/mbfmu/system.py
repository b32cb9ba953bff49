"""`linearize_system(ssp, at)`: the linearization of FMUs coupled in an SSP file.

The system (one flat `<System>` of Co-Simulation components, as fmpy.ssp reads it) is
co-simulated with a fixed communication step (Jacobi: every component steps with the
inputs of the step's start, then the connections are propagated). At each time in `at`
the connections are propagated to a fixed point, every component is linearized there
(linearize_fmu.linearize_at), and the component models are combined exactly:

    u = K y + E w        (component inputs from component outputs and system inputs w)
    y = C x + D u   =>   y = (I − D K)⁻¹ (C x + D E w)
    ẋ = A x + B u,       z = F y + G w   (system outputs z)

with A, B, C, D block-diagonal over the components and K, E, F, G the connections
(with an SSP LinearTransformation's factor). A singular I − D K is an algebraic loop
with no solution: NotLinearizableError.

System inputs are the system's input connectors followed by every unconnected component
input ("component.input"); system outputs are the system's output connectors, or every
component output when the system declares none. States are "component.state".
"""

from __future__ import annotations

import math
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import ArgumentError, FMUNotFoundError, MbfmuError, NotLinearizableError
from .instance import Instance, Opened
from .linearization import DIFFERENCES, DIRECTIONAL, Linearization
from .linearize_fmu import _progress, _warn_differences, check_times, linearize_at
from .structure import Structure, read_structure


@dataclass
class _Component:
    name: str
    opened: Opened
    st: Structure
    inst: Instance | None = None
    start_values: dict = field(default_factory=dict)


def _parameter_values(element) -> dict:
    """Inline <ParameterBindings> of an SSD element: {variable: value}."""
    out = {}
    for b in getattr(element, "parameterBindings", []):
        prefix = b.prefix or ""
        for ps in b.parameterValues:
            for p in ps.parameters:
                if p.type in ("Real", "Integer") and p.value is not None:
                    name = p.name[len(prefix) :] if prefix and p.name.startswith(prefix) else p.name
                    out[name] = float(p.value)
    return out


def _read(ssp: Path):
    from fmpy.ssp.ssd import Component, System, read_ssd

    try:
        ssd = read_ssd(str(ssp), validate=False)
    except Exception as e:
        raise MbfmuError(f"SSP '{ssp}' cannot be read: {e}") from e
    system = ssd.system
    for el in system.elements:
        if isinstance(el, System):
            raise NotLinearizableError(f"SSP '{ssp}': nested system '{el.name}' is not supported (flatten it)")
        if not isinstance(el, Component):
            raise NotLinearizableError(f"SSP '{ssp}': element '{el.name}' is not a component")
    return ssd, system


class _Wiring:
    """The connections as index maps over the stacked component inputs and outputs."""

    def __init__(self, ssp: Path, system, comps: list[_Component]):
        self.u_index: dict[tuple[str, str], int] = {}
        self.y_index: dict[tuple[str, str], int] = {}
        for c in comps:
            for v in c.st.inputs:
                self.u_index[(c.name, v.name)] = len(self.u_index)
            for v in c.st.outputs:
                self.y_index[(c.name, v.name)] = len(self.y_index)
        sys_in = [c.name for c in system.connectors if c.kind == "input"]
        sys_out = [c.name for c in system.connectors if c.kind == "output"]
        names = {c.name for c in comps}
        self.feed: dict[int, tuple[str, int, float]] = {}  # u index -> ('y'|'w', index, factor)
        self.zsrc: dict[int, tuple[str, int, float]] = {}  # z index -> ('y'|'w', index, factor)
        wired_w: dict[str, int] = {n: i for i, n in enumerate(sys_in)}
        z_of = {n: i for i, n in enumerate(sys_out)}
        for con in system.connections:
            factor = 1.0
            lt = getattr(con, "linearTransformation", None)
            if lt is not None:  # an offset shifts the operating point only: no derivative
                factor = float(lt.factor)
            src = self._end(ssp, con.startElement, con.startConnector, names, wired_w, z_of, start=True)
            dst = self._end(ssp, con.endElement, con.endConnector, names, wired_w, z_of, start=False)
            if src is None or dst is None:
                continue  # a non-Real or unknown connector: not part of the linear model
            kind_d, idx_d = dst
            target = self.feed if kind_d == "u" else self.zsrc
            if idx_d in target:
                raise ArgumentError(f"SSP '{ssp}': {con.endElement}.{con.endConnector} has two incoming connections")
            target[idx_d] = (src[0], src[1], factor)
        # Unconnected component inputs become system inputs.
        self.w_names = list(sys_in)
        for (cname, vname), i in self.u_index.items():
            if i not in self.feed:
                self.feed[i] = ("w", len(self.w_names), 1.0)
                self.w_names.append(f"{cname}.{vname}")
        if sys_out:
            self.z_names = list(sys_out)
        else:
            self.z_names = [f"{c}.{v}" for (c, v) in self.y_index]
            self.zsrc = {i: ("y", i, 1.0) for i in range(len(self.y_index))}

    def _end(self, ssp, element, connector, names, w_of, z_of, start: bool):
        if element is None or element == "":
            if start and connector in w_of:
                return ("w", w_of[connector])
            if not start and connector in z_of:
                return ("z", z_of[connector])
            raise ArgumentError(f"SSP '{ssp}': system connector '{connector}' is used against its kind")
        if element not in names:
            raise ArgumentError(f"SSP '{ssp}': connection names an unknown component '{element}'")
        key = (element, connector)
        if start:
            return ("y", self.y_index[key]) if key in self.y_index else None
        return ("u", self.u_index[key]) if key in self.u_index else None

    def matrices(self):
        """K, E (u = K y + E w) and F, G (z = F y + G w)."""
        nu, ny, nw, nz = len(self.u_index), len(self.y_index), len(self.w_names), len(self.z_names)
        K, E = np.zeros((nu, ny)), np.zeros((nu, nw))
        F, G = np.zeros((nz, ny)), np.zeros((nz, nw))
        for i, (kind, j, f) in self.feed.items():
            (K if kind == "y" else E)[i, j] = f
        for i, (kind, j, f) in self.zsrc.items():
            (F if kind == "y" else G)[i, j] = f
        return K, E, F, G


def _block_diag(mats: list[np.ndarray]) -> np.ndarray:
    rows = sum(m.shape[0] for m in mats)
    cols = sum(m.shape[1] for m in mats)
    out = np.zeros((rows, cols))
    r = c = 0
    for m in mats:
        out[r : r + m.shape[0], c : c + m.shape[1]] = m
        r += m.shape[0]
        c += m.shape[1]
    return out


def _combine(
    lins: list[Linearization], wiring: _Wiring, comp_names: list[str], time: float, model: str
) -> Linearization:
    A = _block_diag([lin.A for lin in lins])
    B = _block_diag([lin.B for lin in lins])
    C = _block_diag([lin.C for lin in lins])
    D = _block_diag([lin.D for lin in lins])
    K, E, F, G = wiring.matrices()
    loop = np.eye(D.shape[0]) - D @ K
    if loop.size and (not np.all(np.isfinite(loop)) or np.linalg.cond(loop) > 1e12):
        raise NotLinearizableError(
            f"system '{model}' at t = {time:g}: the algebraic loop through the feedthrough (I − D K) is singular "
            f"(condition number {np.linalg.cond(loop):.3g}); the coupled outputs are not determined"
        )
    M = np.linalg.solve(loop, np.hstack([C, D @ E])) if loop.size else np.zeros((0, C.shape[1] + E.shape[1]))
    My_x, My_w = M[:, : C.shape[1]], M[:, C.shape[1] :]
    sys_A = A + B @ K @ My_x
    sys_B = B @ (K @ My_w + E)
    sys_C = F @ My_x
    sys_D = F @ My_w + G
    states = [f"{c}.{s}" for c, lin in zip(comp_names, lins, strict=True) for s in lin.states]
    units = [u for lin in lins for u in lin.state_units]
    x0 = np.concatenate([lin.x0 for lin in lins]) if lins else np.zeros(0)
    y_all = np.concatenate([lin.y0 for lin in lins]) if lins else np.zeros(0)
    u_all = np.concatenate([lin.u0 for lin in lins]) if lins else np.zeros(0)
    w0 = _w_values(wiring, u_all)
    method = DIRECTIONAL if all(lin.method == DIRECTIONAL for lin in lins) else DIFFERENCES
    y_units = [u for lin in lins for u in lin.output_units]
    u_units = [u for lin in lins for u in lin.input_units]
    return Linearization(
        time=time,
        A=sys_A,
        B=sys_B,
        C=sys_C,
        D=sys_D,
        states=states,
        inputs=list(wiring.w_names),
        outputs=list(wiring.z_names),
        state_units=units,
        input_units=_units_of(wiring, "w", u_units),
        output_units=_units_of(wiring, "z", y_units),
        x0=x0,
        u0=w0,
        y0=F @ y_all + G @ w0,
        method=method,
        model=model,
    )


def _w_values(wiring: _Wiring, u_all: np.ndarray) -> np.ndarray:
    """System input values read back from the component inputs they feed (factor 1 or not)."""
    w = np.zeros(len(wiring.w_names))
    for i, (kind, j, f) in wiring.feed.items():
        if kind == "w" and f != 0:
            w[j] = u_all[i] / f
    return w


def _units_of(wiring: _Wiring, which: str, comp_units: list[str]) -> list[str]:
    if which == "w":
        units = [""] * len(wiring.w_names)
        for i, (kind, j, _) in wiring.feed.items():
            if kind == "w":
                units[j] = comp_units[i]
        return units
    units = [""] * len(wiring.z_names)
    for i, (kind, j, _) in wiring.zsrc.items():
        if kind == "y":
            # comp_units are the stacked component *output* units here
            units[i] = comp_units[j]
    return units


class _Master:
    """Fixed-step Jacobi co-simulation of the components."""

    def __init__(self, comps: list[_Component], wiring: _Wiring, w_values: np.ndarray):
        self.comps = comps
        self.wiring = wiring
        self.w = w_values
        self.y = np.zeros(len(wiring.y_index))
        self.u = np.zeros(len(wiring.u_index))
        self._u_slices, self._y_slices = [], []
        ui = yi = 0
        for c in comps:
            self._u_slices.append(slice(ui, ui + len(c.st.inputs)))
            self._y_slices.append(slice(yi, yi + len(c.st.outputs)))
            ui += len(c.st.inputs)
            yi += len(c.st.outputs)

    def read_outputs(self):
        for c, sl in zip(self.comps, self._y_slices, strict=True):
            self.y[sl] = c.inst.get([v.vr for v in c.st.outputs])

    def write_inputs(self):
        for i, (kind, j, f) in self.wiring.feed.items():
            self.u[i] = f * (self.y[j] if kind == "y" else self.w[j])
        for c, sl in zip(self.comps, self._u_slices, strict=True):
            c.inst.set([v.vr for v in c.st.inputs], self.u[sl])

    def settle(self, passes: int):
        """Propagate outputs to inputs until they stop changing (direct feedthrough chains
        settle in at most one pass per component)."""
        for _ in range(passes):
            before = self.u.copy()
            self.read_outputs()
            self.write_inputs()
            if np.array_equal(before, self.u):
                break

    def step(self, t0: float, h: float):
        for c in self.comps:
            c.inst._call("fmi2DoStep", c.inst.fmu.doStep, currentCommunicationPoint=t0, communicationStepSize=h)
            c.inst.time = t0 + h
        self.read_outputs()
        self.write_inputs()


def linearize_system(
    ssp, at=None, step=None, start_values=None, tolerance=None, progress=False, use_dependencies=True
) -> list[Linearization]:
    """Co-simulate the SSP system `ssp` with communication step `step` (default: the SSD's
    DefaultExperiment stepSize, else 1e-3) and return the linearization of the coupled
    system at each time in `at` (default: the start).

    start_values: {"component.variable": value} (over the SSD's own parameter bindings);
    system inputs that are not components' are held at 0 (or {"input": value}).
    """
    ssp = Path(ssp)
    if not ssp.exists():
        raise FMUNotFoundError(f"SSP '{ssp}' does not exist")
    ssd, system = _read(ssp)
    start, stop, h = _experiment(ssp, step)
    comps: list[_Component] = []
    sv_all = dict(start_values or {})
    tmp_fmus = []
    try:
        with zipfile.ZipFile(ssp) as zf:
            import tempfile

            root = tempfile.mkdtemp(prefix="mbfmu_ssp_")
            tmp_fmus.append(root)
            for el in system.elements:
                if not el.source or el.source not in zf.namelist():
                    raise ArgumentError(f"SSP '{ssp}': component '{el.name}' source '{el.source}' is not in the SSP")
                path = Path(zf.extract(el.source, root))
                op = Opened(path)
                interface = "CoSimulation"
                if op.md.coSimulation is None:
                    raise NotLinearizableError(f"SSP '{ssp}': component '{el.name}' is not a Co-Simulation FMU")
                comps.append(_Component(el.name, op, read_structure(op.md, interface)))
        names = {c.name for c in comps}
        for key in sv_all:
            head = key.split(".", 1)[0]
            if head not in names and key not in [c.name for c in system.connectors]:
                raise ArgumentError(
                    f"start value '{key}': expected 'component.variable' with a component of {sorted(names)}"
                )
        for c, el in zip(comps, system.elements, strict=True):
            c.start_values = {
                **_parameter_values(el),
                **{k.split(".", 1)[1]: v for k, v in sv_all.items() if k.startswith(c.name + ".")},
            }
        wiring = _Wiring(ssp, system, comps)
        times = check_times(f"system '{ssd.name}'", at, start)
        w0 = np.array([float(sv_all.get(n, 0.0)) for n in wiring.w_names])
        for c in comps:
            _warn_differences(c.st)
            c.inst = Instance(c.opened.unzipdir, c.opened.md, "CoSimulation", tolerance)
            c.inst.initialize(start, c.start_values)
        master = _Master(comps, wiring, w0)
        master.settle(len(comps) + 1)
        order = sorted(range(len(times)), key=lambda i: times[i])
        out: list[Linearization | None] = [None] * len(times)
        t = start
        k = 0
        for i in _progress(order, progress, len(order), f"linearizing {ssd.name}"):
            target = times[i]
            while t < target * (1 - 1e-12) - 1e-300:
                t_next = min(start + (k + 1) * h, target)
                master.step(t, t_next - t)
                if math.isclose(t_next, start + (k + 1) * h, rel_tol=1e-12, abs_tol=1e-15):
                    k += 1
                t = t_next
            master.settle(len(comps) + 1)
            lins = [linearize_at(c.inst, c.st, use_dependencies) for c in comps]
            out[i] = _combine(lins, wiring, [c.name for c in comps], t, ssd.name or ssp.stem)
        return out  # type: ignore[return-value]
    finally:
        for c in comps:
            if c.inst is not None:
                c.inst.close()
            c.opened.close()
        import shutil

        for d in tmp_fmus:
            shutil.rmtree(d, ignore_errors=True)


def _experiment(ssp: Path, step):
    """Start, stop and communication step from the SSD's DefaultExperiment (and `step`)."""
    import xml.etree.ElementTree as ET

    start, stop, h = 0.0, None, None
    with zipfile.ZipFile(ssp) as zf:
        root = ET.fromstring(zf.read("SystemStructure.ssd"))
    for el in root.iter():
        if el.tag.endswith("DefaultExperiment"):
            start = float(el.get("startTime", 0.0))
            stop = el.get("stopTime")
        if el.tag.endswith("FixedStepMaster") or el.tag.endswith("VariableStepMaster"):
            h = el.get("stepSize") or el.get("maxStepSize")
    h = step if step is not None else (float(h) if h is not None else 1e-3)
    if not (h > 0 and math.isfinite(h)):
        raise ArgumentError(f"step: {h} must be a positive communication step")
    return start, (float(stop) if stop is not None else None), float(h)
