"""fmi2GetFMUstate / fmi2SetFMUstate and their serialized form rewind an instance exactly."""

import pytest

from fmu_helpers import initialize, new_slave, steps

TOL = 1e-8
H = 0.05
N1 = round(1.0 / H)  # to t = 1
N2 = round(1.0 / H)  # then to t = 2


@pytest.mark.parametrize("name", ["double_pendulum", "fourbar"])
def test_rewind_to_a_saved_state_repeats_the_steps_bit_for_bit(name, packed):
    p = packed(name)
    vrs = p.output_vrs
    s = new_slave(p, "rewind")
    try:
        initialize(s, TOL)
        steps(s, vrs, 0.0, H, N1)
        at1 = s.getReal(vrs)
        state = s.getFMUstate()
        first = steps(s, vrs, 1.0, H, N2)
        s.setFMUstate(state)
        # Exact (==): the state holds everything the integrator uses (step history, step
        # size, Newton and Jacobian data), so the same calls repeat the same arithmetic.
        assert s.getReal(vrs) == at1
        again = steps(s, vrs, 1.0, H, N2)
        assert again == first
        assert first[-1] != at1  # it did move
        s.freeFMUstate(state)
    finally:
        s.terminate()
        s.freeInstance()


@pytest.mark.parametrize("name", ["double_pendulum", "fourbar"])
def test_serialized_state_continues_in_a_new_instance_bit_for_bit(name, packed):
    p = packed(name)
    vrs = p.output_vrs
    a = new_slave(p, "source")
    b = None
    try:
        initialize(a, TOL)
        steps(a, vrs, 0.0, H, N1)
        at1 = a.getReal(vrs)
        state = a.getFMUstate()
        data = a.serializeFMUstate(state)
        a.freeFMUstate(state)
        assert isinstance(data, bytes) and len(data) > 0
        first = steps(a, vrs, 1.0, H, N2)

        # A new instance, initialized as usual (at t = 0), then given the state of t = 1.
        b = new_slave(p, "target")
        initialize(b, TOL)
        restored = b.deSerializeFMUstate(data)
        b.setFMUstate(restored)
        b.freeFMUstate(restored)
        assert b.getReal(vrs) == at1  # exact, as above
        assert steps(b, vrs, 1.0, H, N2) == first
    finally:
        a.terminate()
        a.freeInstance()
        if b is not None:
            b.terminate()
            b.freeInstance()


def test_a_restored_state_brings_back_the_input_and_its_slope(rotor):
    vr = rotor.vr
    s = new_slave(rotor, "inputs")
    b = None
    try:
        initialize(s, TOL)
        s.setReal([vr["T"]], [2.0])
        s.setRealInputDerivatives([vr["T"]], [1], [3.0])  # T(t) = 2 + 3 t
        s.doStep(0.0, 0.5)
        state = s.getFMUstate()
        data = s.serializeFMUstate(state)
        s.doStep(0.5, 0.5)
        first = s.getReal([vr["w"], vr["T"]])
        # J w(1) = 2 + 3/2 and T(1) = 5; 1e-10 as in test_fmu_inputs (exact polynomial).
        assert first[0] == pytest.approx(3.5 / 0.5, abs=1e-10) and first[1] == pytest.approx(5.0, abs=1e-12)

        s.setFMUstate(state)
        s.setReal([vr["T"]], [-7.0])  # a new constant input, then back to the saved state
        s.setFMUstate(state)
        s.doStep(0.5, 0.5)
        assert s.getReal([vr["w"], vr["T"]]) == first  # exact: the state includes both
        s.freeFMUstate(state)

        b = new_slave(rotor, "inputs2")
        initialize(b, TOL)  # T = 0, no slope
        restored = b.deSerializeFMUstate(data)
        b.setFMUstate(restored)
        b.freeFMUstate(restored)
        b.doStep(0.5, 0.5)
        assert b.getReal([vr["w"], vr["T"]]) == first
    finally:
        s.terminate()
        s.freeInstance()
        if b is not None:
            b.terminate()
            b.freeInstance()
