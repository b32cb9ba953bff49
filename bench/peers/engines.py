"""One run of the chain in each engine: mbfmu (CLI and FMU), Exudyn, MuJoCo.

Every run starts from the same pose (joint angles theta, zero velocities) and returns a
Run: the wall and CPU time of the timed part, the tip of the last link at the sample
times, and notes. What is timed:
  mbfmu CLI  the whole `mbfmu simulate` process (parse, assembly, integration, CSV output)
  mbfmu FMU  the doStep loop only (with one fmi2GetReal of the tip per step);
             instantiate + initialization is reported apart (init_s)
  Exudyn     mbs.SolveDynamic (its initial accelerations included; model building and
             Assemble not)
  MuJoCo     mujoco.mj_step(model, data, nstep) (compilation not)
"""

from __future__ import annotations

import csv
import io
import resource
import subprocess
import time
from dataclasses import dataclass, field

import numpy as np

from chain import Chain, G, set_args


@dataclass
class Run:
    wall: float  # seconds, the timed part
    cpu: float  # seconds of CPU, the timed part
    steps: int  # steps taken (fixed-step engines) or communication steps (mbfmu)
    t: np.ndarray  # sample times
    tip: np.ndarray  # (len(t), 3) tip of the last link
    extra: dict = field(default_factory=dict)

    def tip_at(self, when: float) -> np.ndarray:
        """The tip at a sample time; between samples (Exudyn's sensor after adaptive step
        cuts records near, not at, its write times) linearly interpolated."""
        i = int(np.argmin(np.abs(self.t - when)))
        if abs(self.t[i] - when) < 1e-9:
            return self.tip[i]
        return np.array([np.interp(when, self.t, self.tip[:, j]) for j in range(3)])


def _read_csv(text: str) -> dict[str, np.ndarray]:
    rows = list(csv.reader(io.StringIO(text)))
    cols = np.array(rows[1:], dtype=float)
    return {name: cols[:, j] for j, name in enumerate(rows[0])}


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def mbfmu_cli(
    binary: str, model: str, *, tol: float, step: float, end: float = 1.0, timeout: float | None = None
) -> Run:
    """`mbfmu simulate model --end END --step STEP --tol TOL --set <pose>`, timed as a process."""
    cmd = [binary, "simulate", model, "--end", repr(end), "--step", repr(step), "--tol", repr(tol), *set_args()]
    cpu0, t0 = _children_cpu(), time.perf_counter()
    res = subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=timeout)
    wall, cpu = time.perf_counter() - t0, _children_cpu() - cpu0
    if res.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: exit {res.returncode}: {res.stderr.strip()}")
    d = _read_csv(res.stdout)
    tip = np.column_stack([d["tip_x"], d["tip_y"], d["tip_z"]])
    return Run(wall, cpu, len(d["time"]) - 1, d["time"], tip)


def mbfmu_pose(binary: str, pose_model: str) -> tuple[np.ndarray, np.ndarray]:
    """The joint angles and the tip of mbfmu's assembled start (the pose model's outputs at t = 0)."""
    cmd = [binary, "simulate", pose_model, "--end", "0", *set_args()]
    d = _read_csv(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
    n = sum(1 for k in d if k.startswith("a"))
    theta = np.array([d[f"a{k}"][0] for k in range(1, n + 1)])
    return theta, np.array([d["tip_x"][0], d["tip_y"][0], d["tip_z"][0]])


def mbfmu_fmu(fmu_path: str, *, tol: float, step: float, end: float = 1.0) -> Run:
    """fmpy's low-level FMU2Slave: instantiate, setupExperiment(tol), init, doStep loop."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(fmu_path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    tip_vrs = [vr["tip_x"], vr["tip_y"], vr["tip_z"]]
    unzipdir = extract(fmu_path)
    fmu = FMU2Slave(
        guid=md.guid,
        unzipDirectory=unzipdir,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="chain",
    )
    n = round(end / step)
    t0 = time.perf_counter()
    fmu.instantiate()
    fmu.setupExperiment(tolerance=tol, startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    init_s = time.perf_counter() - t0
    tip = np.empty((n + 1, 3))
    tip[0] = fmu.getReal(tip_vrs)
    cpu0, t0 = time.process_time(), time.perf_counter()
    for k in range(n):
        fmu.doStep(currentCommunicationPoint=k * step, communicationStepSize=step)
        tip[k + 1] = fmu.getReal(tip_vrs)
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    fmu.terminate()
    fmu.freeInstance()
    return Run(wall, cpu, n, np.arange(n + 1) * step, tip, {"init_s": init_s})


def exudyn_run(
    chain: Chain,
    theta: np.ndarray,
    *,
    h: float,
    end: float = 1.0,
    sample: float | None = None,
    adaptive_fallback: bool = True,
) -> Run:
    """Redundant coordinates (rigid bodies with Euler parameters, revolute joints),
    generalized-alpha (SolveDynamic, default spectral radius 0.9), fixed step h, sparse
    solver; the tip position recorded by a body sensor every step (or every `sample`)."""
    import exudyn as exu
    from exudyn.utilities import ObjectGround, RigidBodyInertia, SensorBody

    rot, piv, cm, _ = chain.pose(theta)
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    prev = ground
    bodies = []
    for k in range(chain.n):
        inertia = RigidBodyInertia(mass=chain.mass[k], inertiaTensor=np.diag(chain.inertia[k]))
        b = mbs.CreateRigidBody(
            referencePosition=cm[k], referenceRotationMatrix=rot[k], inertia=inertia, gravity=[0.0, 0.0, -G]
        )
        mbs.CreateRevoluteJoint(itemNumbers=[prev, b], position=piv[k], axis=rot[k] @ chain.axis[k])
        bodies.append(b)
        prev = b
    sensor = mbs.AddSensor(
        SensorBody(
            bodyNumber=bodies[-1],
            localPosition=list(chain.tip[-1]),
            outputVariableType=exu.OutputVariableType.Position,
            storeInternal=True,
            writeToFile=False,
        )
    )
    mbs.Assemble()

    n = round(end / h)
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.numberOfSteps = n
    ti.endTime = end
    ti.adaptiveStep = False  # fixed h
    ti.verboseMode = 0
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    s.solution.file.write = False
    s.solution.sensors.writePeriod = h if sample is None else sample
    s.show.globalTimers = False
    s.show.computationTime = False
    extra = {}
    cpu0, t0 = time.process_time(), time.perf_counter()
    try:
        ok = mbs.SolveDynamic(s, solverType=exu.DynamicSolverType.GeneralizedAlpha)
    except exu.SolverError:
        ok = False
    if not ok and not adaptive_fallback:
        raise RuntimeError(f"Exudyn SolveDynamic failed with fixed h = {h:g}")
    if not ok:
        # Newton did not converge with the fixed step: where, then again with Exudyn's
        # default adaptiveStep (the step is cut only where Newton fails); both timed.
        failed_at = float(np.asarray(mbs.GetSensorStoredData(sensor))[-1, 0])
        ti.adaptiveStep = True  # SolveDynamic starts again from the initial values
        ok = mbs.SolveDynamic(s, solverType=exu.DynamicSolverType.GeneralizedAlpha)
        if not ok:
            raise RuntimeError("Exudyn SolveDynamic failed with adaptiveStep too")
        extra["note"] = f"fixed h failed (Newton) at t={failed_at:.3f} s; rerun with adaptiveStep, both timed"
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    data = np.asarray(mbs.GetSensorStoredData(sensor))
    return Run(wall, cpu, n, data[:, 0], data[:, 1:4], extra)


def mujoco_xml(chain: Chain, *, dt: float) -> str:
    """Minimal coordinates: body k's frame sits at its joint (the top marker), axes as drawn,
    a hinge about the drawn joint axis, explicit inertial; RK4, contacts disabled."""
    f = "{:.17g}".format

    def v(x: np.ndarray) -> str:
        return " ".join(f(c) for c in x)

    lines = [
        f'<mujoco model="chain{chain.n}">',
        '  <compiler angle="radian"/>',
        f'  <option timestep="{f(dt)}" integrator="RK4" gravity="0 0 {f(-G)}">',
        '    <flag contact="disable"/>',
        "  </option>",
        "  <worldbody>",
    ]
    pos = np.zeros(3)
    for k in range(chain.n):
        ind = "    " + "  " * k
        lines.append(f'{ind}<body name="l{k + 1}" pos="{v(pos)}">')
        lines.append(f'{ind}  <joint name="j{k + 1}" type="hinge" pos="0 0 0" axis="{v(chain.axis[k])}"/>')
        i = chain.inertia[k]
        lines.append(f'{ind}  <inertial pos="{v(-chain.top[k])}" mass="{f(chain.mass[k])}" diaginertia="{v(i)}"/>')
        pos = chain.tip[k] - chain.top[k]  # the child's joint, in this body's frame
    lines.append(f'{"    " + "  " * (chain.n - 1)}  <site name="tip" pos="{v(pos)}"/>')
    for k in reversed(range(chain.n)):
        lines.append(f"{'    ' + '  ' * k}</body>")
    lines += ["  </worldbody>", "</mujoco>", ""]
    return "\n".join(lines)


def mujoco_run(chain: Chain, theta: np.ndarray, *, dt: float, end: float = 1.0, sample: float | None = 0.01) -> Run:
    """Timed: one mj_step(model, data, nstep=end/dt). Then, untimed, the same run again in
    chunks of `sample` for the tip's trajectory (the two final states are compared);
    sample None: only the start and the end."""
    import mujoco

    model = mujoco.MjModel.from_xml_string(mujoco_xml(chain, dt=dt))
    site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "tip")
    n = round(end / dt)

    def start() -> mujoco.MjData:
        data = mujoco.MjData(model)
        data.qpos[:] = theta
        data.qvel[:] = 0.0
        mujoco.mj_forward(model, data)
        return data

    data = start()
    tip0 = data.site_xpos[site].copy()
    cpu0, t0 = time.process_time(), time.perf_counter()
    mujoco.mj_step(model, data, nstep=n)
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    mujoco.mj_forward(model, data)
    tip_end = data.site_xpos[site].copy()
    # MuJoCo resets the state (to the drawn pose) when it meets a NaN or a huge value:
    # such a run is unstable, not merely inaccurate.
    bad = [mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQVEL, mujoco.mjtWarning.mjWARN_BADQPOS]
    extra = {"note": "unstable: MuJoCo reset the state"} if any(data.warning[w].number for w in bad) else {}

    if sample is None:
        return Run(wall, cpu, n, np.array([0.0, n * dt]), np.array([tip0, tip_end]), extra)
    per = max(1, round(sample / dt))
    data = start()
    ts, tips = [0.0], [tip0]
    for k in range(per, n + 1, per):
        mujoco.mj_step(model, data, nstep=per)
        mujoco.mj_forward(model, data)
        ts.append(k * dt)
        tips.append(data.site_xpos[site].copy())
    assert extra or np.allclose(tips[-1], tip_end, rtol=0, atol=1e-12), "chunked MuJoCo run differs from the timed one"
    return Run(wall, cpu, n, np.array(ts), np.array(tips), extra)
