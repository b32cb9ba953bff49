"""Nothing a host does crashes its process: FMU calls from a thread with a 128 KiB stack,
a logger callback that calls back into the instance, FMU-state handles that are stale or
belong to another instance, a component that was freed."""

import json
import subprocess
import sys
from ctypes import byref, c_double, c_uint, c_void_p

import pytest
from fmpy.fmi2 import FMU2Slave

from fmu_helpers import MODELS, LogCapture, _Logger6, fmi2CallbackLoggerTYPE, initialize, new_slave

FMI_ERROR = 3

# Every example model (those with flexible bodies, in models/flexible/, included); the
# run below initializes, steps, reads all of A/B/C/D and round-trips the FMU state.
EXAMPLES = sorted(p.stem for p in MODELS.glob("*.xml")) + sorted(
    f"flexible/{p.stem}" for p in (MODELS / "flexible").glob("*.xml")
)

# The whole run, in a thread whose stack is `stack` bytes, printed as JSON. It runs in a
# child process so that a stack overflow shows as a failed test (exit by signal), not as
# the end of the test session.
CHILD = r"""
import json, sys, threading
from fmpy.fmi2 import FMU2Slave

unzipped, guid, ident, stack, knowns, unknowns, tol, h = json.loads(sys.argv[1])
out = {}

def run():
    s = FMU2Slave(guid=guid, unzipDirectory=unzipped, modelIdentifier=ident, instanceName="small")
    s.instantiate()
    s.setupExperiment(tolerance=tol, startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, h)
    state = s.getFMUstate()
    s.doStep(h, h)
    data = s.serializeFMUstate(state)
    s.freeFMUstate(state)
    back = s.deSerializeFMUstate(data)
    s.setFMUstate(back)
    s.freeFMUstate(back)
    s.doStep(h, h)
    out["jacobian"] = [s.getDirectionalDerivative(unknowns, [k], [1.0]) for k in knowns]
    out["states"] = s.getReal(knowns)
    s.terminate()
    s.freeInstance()

def guarded():
    try:
        run()
    except BaseException as e:  # reported by the exit code, not only printed
        out["error"] = repr(e)

threading.stack_size(stack)
t = threading.Thread(target=guarded)
t.start()
t.join()
if "error" in out:
    sys.exit("in the thread: " + out["error"])
print(json.dumps(out))
"""


def raw(s, name):
    """The FMU's function `name` itself, returning its status (fmpy's wrapper raises)."""
    return getattr(s.dll, name)


def structure(p):
    """(knowns, unknowns) value references: states and inputs; state derivatives and outputs."""
    mv = p.md.modelVariables
    ders = [d.variable for d in p.md.derivatives]
    states = [d.derivative.valueReference for d in ders]
    inputs = [v.valueReference for v in mv if v.causality == "input"]
    outputs = [v.valueReference for v in mv if v.causality == "output"]
    return states + inputs, [d.valueReference for d in ders] + outputs


def run_in_thread(p, stack: int, tol: float = 1e-8, h: float = 0.01) -> dict:
    knowns, unknowns = structure(p)
    args = [str(p.unzipped), p.md.guid, p.md.coSimulation.modelIdentifier, stack, knowns, unknowns, tol, h]
    r = subprocess.run([sys.executable, "-c", CHILD, json.dumps(args)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, f"exit {r.returncode} (negative: killed by signal): {r.stderr[-2000:]}"
    return json.loads(r.stdout)


@pytest.mark.parametrize("name", EXAMPLES)
def test_every_call_works_from_a_thread_with_a_128_kib_stack(packed, name):
    p = packed(name)
    small = run_in_thread(p, 128 * 1024)
    # The same run on an 8 MiB thread stack: the engine's arithmetic does not depend on
    # which stack it runs on, so A/B/C/D and the states agree bit for bit.
    large = run_in_thread(p, 8 << 20)
    assert small == large
    assert len(small["jacobian"]) == len(structure(p)[0])


def test_a_logger_that_calls_back_into_the_instance_gets_fmi2error(packed):
    p = packed("pendulum")
    vr = p.vr
    seen = []  # (message, status of the nested fmi2GetReal)
    holder = {}

    def log(env, name, status, category, fmt, text):
        s = holder["slave"]
        value = c_double()
        ref = c_uint(vr["angle"])
        nested = raw(s, "fmi2GetReal")(s.component, byref(ref), 1, byref(value))
        seen.append((text.decode(), nested))

    cap = LogCapture()
    fn = _Logger6(log)
    cap.callbacks.logger = fmi2CallbackLoggerTYPE(c_void_p.from_buffer(fn).value)
    s = FMU2Slave(
        guid=p.md.guid,
        unzipDirectory=str(p.unzipped),
        modelIdentifier=p.md.coSimulation.modelIdentifier,
        instanceName="reentrant",
    )
    holder["slave"] = s
    s.instantiate(callbacks=cap.callbacks)
    try:
        initialize(s, 1e-8)
        ref = c_uint(999_999)
        value = c_double()
        assert raw(s, "fmi2GetReal")(s.component, byref(ref), 1, byref(value)) == FMI_ERROR
        # The error reached the logger, whose nested call on the same instance was
        # refused (fmi2Error) and reported; the logger's nested call while that report
        # was delivered was refused too, without a further report, so a logger that
        # always calls back cannot recurse. The inner callback returns first.
        assert [m.split(":")[0] for m, _ in seen] == ["fmi2GetReal", "fmi2GetReal"]
        assert "another call on this instance is still running" in seen[0][0]
        assert seen[1][0].startswith("fmi2GetReal: unknown value reference 999999")
        assert [status for _, status in seen] == [FMI_ERROR, FMI_ERROR]
        # The instance is intact: the same read now succeeds, a step works.
        s.doStep(0.0, 0.01)
        assert len(s.getReal([vr["angle"]])) == 1
    finally:
        s.terminate()
        s.freeInstance()
    del fn


def test_fmu_state_handles_of_another_instance_or_already_freed_are_refused(packed):
    p = packed("pendulum")
    log = LogCapture()
    a = new_slave(p, "a", log=log)
    b = new_slave(p, "b", log=log)
    try:
        initialize(a, 1e-8)
        initialize(b, 1e-8)
        sa = a.getFMUstate()
        handle = sa.value
        assert raw(b, "fmi2SetFMUstate")(b.component, c_void_p(handle)) == FMI_ERROR
        assert "not a live state of this instance" in log.messages(FMI_ERROR)[-1]
        a.freeFMUstate(sa)
        assert raw(a, "fmi2SetFMUstate")(a.component, c_void_p(handle)) == FMI_ERROR
        stale = c_void_p(handle)
        assert raw(a, "fmi2FreeFMUstate")(a.component, byref(stale)) == FMI_ERROR
        # Both instances go on.
        a.doStep(0.0, 0.01)
        b.doStep(0.0, 0.01)
    finally:
        for s in (a, b):
            s.terminate()
            s.freeInstance()


def test_a_freed_component_is_refused_not_dereferenced(packed):
    p = packed("pendulum")
    # A second load of the same library keeps it mapped after fmpy's freeInstance
    # unloads its own (dlopen counts references).
    keeper = FMU2Slave(
        guid=p.md.guid,
        unzipDirectory=str(p.unzipped),
        modelIdentifier=p.md.coSimulation.modelIdentifier,
        instanceName="keeper",
    )
    s = new_slave(p, "freed")
    initialize(s, 1e-8)
    dead = s.component
    s.terminate()
    s.freeInstance()
    try:
        value = c_double()
        ref = c_uint(p.vr["angle"])
        assert raw(keeper, "fmi2GetReal")(dead, byref(ref), 1, byref(value)) == FMI_ERROR
        assert raw(keeper, "fmi2DoStep")(dead, 0.0, 0.01, 1) == FMI_ERROR
        raw(keeper, "fmi2FreeInstance")(dead)  # a second free does nothing
        assert raw(keeper, "fmi2GetReal")(None, byref(ref), 1, byref(value)) == FMI_ERROR
    finally:
        keeper.freeLibrary()
