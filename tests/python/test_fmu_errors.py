"""Refused calls: fmi2Error, a logged message naming the function and the offending value,
nothing changed, and the instance still works."""

import math

import pytest
from fmpy.fmi1 import FMICallException  # fmpy raises it for every status above fmi2Warning
from fmpy.fmi2 import fmi2Error

from fmu_helpers import LogCapture, initialize, new_slave

J = 0.5


@pytest.fixture
def logged(rotor):
    """(slave, log capture, value references) of a rotor instance, logging off: errors
    must reach the host anyway."""
    log = LogCapture()
    s = new_slave(rotor, "checked", log=log, logging_on=False)
    yield s, log, rotor.vr
    try:
        s.terminate()
    except FMICallException:
        pass  # never initialized: nothing to terminate
    s.freeInstance()


def refused(call, function: str, log: LogCapture, *needles: str) -> str:
    """`call()` raises FMICallException(function, fmi2Error), and exactly one message was
    logged for it: status fmi2Error, category logStatusError, format "%s", naming the
    function and every needle. Returns the message."""
    log.clear()
    with pytest.raises(FMICallException) as e:
        call()
    assert (e.value.function, e.value.status) == (function, fmi2Error)
    assert len(log.records) == 1, log.records
    name, status, category, fmt, text = log.records[0]
    assert (name, status, category, fmt) == ("checked", fmi2Error, "logStatusError", "%s")
    assert text.startswith(f"{function}:"), text
    for n in needles:
        assert n in text, (n, text)
    log.clear()
    return text


def test_unknown_value_reference_is_refused_and_named(logged):
    s, log, vr = logged
    initialize(s, 1e-8)
    refused(lambda: s.getReal([9999]), "fmi2GetReal", log, "9999")
    refused(lambda: s.getReal([vr["w"], 9999]), "fmi2GetReal", log, "9999")
    assert s.getReal([vr["w"], vr["J"]]) == [0.0, J]
    s.doStep(0.0, 0.1)
    assert not log.records


def test_do_step_before_initialization_is_refused_and_names_the_state(logged):
    s, log, vr = logged
    refused(lambda: s.doStep(0.0, 0.1), "fmi2DoStep", log, "Instantiated")
    s.setupExperiment(tolerance=1e-8, startTime=0.0)
    s.enterInitializationMode()
    refused(lambda: s.doStep(0.0, 0.1), "fmi2DoStep", log, "InitializationMode")
    s.setReal([vr["T"]], [2.0])
    s.exitInitializationMode()
    s.doStep(0.0, 0.1)
    # Tolerance 1e-10: exact polynomial solution, see test_fmu_inputs.
    assert s.getReal([vr["w"]])[0] == pytest.approx(2.0 * 0.1 / J, abs=1e-10)


def test_nan_input_is_refused_and_changes_nothing(logged):
    s, log, vr = logged
    initialize(s, 1e-8, values={vr["T"]: 1.0})
    refused(lambda: s.setReal([vr["T"]], [math.nan]), "fmi2SetReal", log, "NaN", "'T'")
    refused(lambda: s.setReal([vr["T"]], [math.inf]), "fmi2SetReal", log, "inf", "'T'")
    s.doStep(0.0, 0.1)  # still T = 1
    assert s.getReal([vr["w"]])[0] == pytest.approx(1.0 * 0.1 / J, abs=1e-10)
    s.setReal([vr["T"]], [3.0])
    s.doStep(0.1, 0.1)
    assert s.getReal([vr["w"]])[0] == pytest.approx((0.1 + 0.3) / J, abs=1e-10)


def test_parameter_set_after_initialization_is_refused_and_changes_nothing(logged):
    s, log, vr = logged
    initialize(s, 1e-8, values={vr["T"]: 1.0})
    refused(lambda: s.setReal([vr["J"]], [2.0]), "fmi2SetReal", log, "'J'", "after initialization")
    # Refused as a whole: the input given with it is not applied either.
    refused(lambda: s.setReal([vr["T"], vr["J"]], [5.0, 2.0]), "fmi2SetReal", log, "'J'")
    assert s.getReal([vr["J"]]) == [J]
    s.doStep(0.0, 0.1)
    assert s.getReal([vr["w"]])[0] == pytest.approx(1.0 * 0.1 / J, abs=1e-10)


def test_setting_an_output_is_refused_in_every_state(logged):
    s, log, vr = logged
    out = vr["w"]
    refused(lambda: s.setReal([out], [1.0]), "fmi2SetReal", log, "'w'", "output")
    s.setupExperiment(tolerance=1e-8, startTime=0.0)
    s.enterInitializationMode()
    refused(lambda: s.setReal([out], [1.0]), "fmi2SetReal", log, "'w'", "output")
    s.exitInitializationMode()
    refused(lambda: s.setReal([out], [1.0]), "fmi2SetReal", log, "'w'", "output")
    assert s.getReal([out]) == [0.0]
    s.setReal([vr["T"]], [2.0])
    s.doStep(0.0, 0.1)
    assert s.getReal([out])[0] == pytest.approx(2.0 * 0.1 / J, abs=1e-10)


def test_step_from_a_wrong_time_or_past_stop_time_is_refused(logged):
    s, log, vr = logged
    initialize(s, 1e-8, stop=1.0, values={vr["T"]: 1.0})
    refused(lambda: s.doStep(0.1, 0.1), "fmi2DoStep", log, "currentCommunicationPoint 0.1", "current time 0")
    refused(lambda: s.doStep(0.0, 2.0), "fmi2DoStep", log, "beyond stopTime 1")
    refused(lambda: s.doStep(0.0, -0.1), "fmi2DoStep", log, "-0.1")
    s.doStep(0.0, 1.0)
    assert s.getReal([vr["w"]])[0] == pytest.approx(1.0 / J, abs=1e-10)


def test_a_state_of_another_fmu_or_garbage_is_refused(logged, packed):
    s, log, vr = logged
    initialize(s, 1e-8)
    other = new_slave(packed("pendulum"), "other")
    try:
        initialize(other, 1e-8)
        st = other.getFMUstate()
        foreign = other.serializeFMUstate(st)
        other.freeFMUstate(st)
    finally:
        other.terminate()
        other.freeInstance()
    refused(
        lambda: s.deSerializeFMUstate(foreign),
        "fmi2DeSerializeFMUstate",
        log,
        "belongs to FMU",
        packed("pendulum").md.guid,
    )
    refused(lambda: s.deSerializeFMUstate(b"garbage"), "fmi2DeSerializeFMUstate", log, "not a serialized state")
    own = s.getFMUstate()
    restored = s.deSerializeFMUstate(s.serializeFMUstate(own))
    s.setFMUstate(restored)
    s.freeFMUstate(own)
    s.freeFMUstate(restored)
    s.doStep(0.0, 0.1)


def test_assembly_that_moves_a_body_far_is_logged_as_a_warning(tmp_path):
    # The FMU logger tells the host what `mbfmu check` prints: a 0.2 m typo in rod2's
    # position is assembled away, and the instance logs which body moved and how far.
    from fmu_helpers import MODELS, LogCapture, initialize, new_slave, pack_model

    text = (
        (MODELS / "double_pendulum.xml")
        .read_text()
        .replace('position="-L*sin(th1) - L/2*sin(th2), 0,', 'position="0.2 - L*sin(th1) - L/2*sin(th2), 0,')
    )
    model = tmp_path / "double_pendulum_typo.xml"
    model.write_text(text)
    p = pack_model(model, tmp_path)
    log = LogCapture()
    s = new_slave(p, log=log, logging_on=True)
    initialize(s, tol=1e-8)
    warnings = [m for m in log.messages(status=1) if "assembly moved body 'rod2' by " in m]
    assert warnings, log.records
    s.terminate()
    s.freeInstance()
