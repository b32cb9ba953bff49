"""mbfmu.linearize on mbfmu's own FMUs: the same A, B, C, D as `mbfmu linearize` (an
independent path: the engine called directly, no FMI), the same names, and the published
eigenvalues of the benchmark bicycle."""

import numpy as np
import pytest
from conftest import MODELS, cli_linearize
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave

import mbfmu

# The example models, those with flexible bodies (models/flexible/, with their modal data
# files) included.
ALL_MODELS = sorted(p.stem for p in MODELS.glob("*.xml")) + sorted(
    f"flexible/{p.stem}" for p in (MODELS / "flexible").glob("*.xml")
)


@pytest.mark.parametrize("name", ALL_MODELS)
def test_package_equals_the_cli_on_every_example_model(packed, tmp_path, name):
    # Both run the same engine through the same times with one advance per time (the CLI
    # directly, the FMU through fmi2DoStep and fmi2GetDirectionalDerivative); 1e-9
    # relative to the largest entry covers summation order in the grouped seeds.
    at = [0.0, 0.3]
    ref = cli_linearize(MODELS / f"{name}.xml", at, 1e-8, tmp_path / "ref.json")
    lins = mbfmu.linearize(packed(name), at=at, tolerance=1e-8)
    assert len(lins) == len(ref)
    for lin, r in zip(lins, ref, strict=True):
        assert lin.time == pytest.approx(r["time"], abs=1e-15)
        assert lin.states == r["states"]
        assert lin.inputs == r["inputs"]
        assert lin.outputs == r["outputs"]
        assert lin.method == "directional derivatives"
        for k in "ABCD":
            got = getattr(lin, k)
            want = np.asarray(r[k], dtype=float).reshape(got.shape)
            scale = max(1.0, float(np.max(np.abs(want)))) if want.size else 1.0
            assert np.max(np.abs(got - want), initial=0.0) <= 1e-9 * scale, (name, k)


def test_results_come_back_in_the_order_asked(packed):
    p = packed("double_pendulum")
    a = mbfmu.linearize(p, at=[0.4, 0.1], tolerance=1e-8)
    b = mbfmu.linearize(p, at=[0.1, 0.4], tolerance=1e-8)
    assert [lin.time for lin in a] == [0.4, 0.1]
    assert np.array_equal(a[0].A, b[1].A) and np.array_equal(a[1].A, b[0].A)


def test_benchmark_bicycle_published_eigenvalues_at_5_m_per_s(packed):
    # Meijaard, Papadopoulos, Ruina, Schwab 2007, Table 2 at v = 5 m/s (7 digits printed):
    # the six other eigenvalues are zero (s0 = 7 position, s1 = 3 velocity states).
    lin = mbfmu.linearize(packed("benchmark_bicycle"), at=0.0, start_values={"v": 5.0}, tolerance=1e-10)[0]
    ev = lin.eigenvalues()
    nonzero = np.sort_complex(ev[np.abs(ev) > 1e-6])
    want = np.sort_complex(np.array([-14.0783897, -0.3228664, -0.7753419 + 4.4648677j, -0.7753419 - 4.4648677j]))
    assert np.max(np.abs(nonzero - want)) < 1e-6
    rows = lin.eigen_table()
    pair = [r for r in rows if r.imag > 0]
    assert len(pair) == 1 and pair[0].imag == pytest.approx(4.4648677, abs=1e-6)
    assert pair[0].frequency_hz == pytest.approx(pair[0].frequency / (2 * np.pi), rel=1e-15)


def test_operating_point_values_are_the_fmu_values(packed):
    lin = mbfmu.linearize(packed("cart_pendulum_pid"), at=0.0, start_values={"r": 0.1}, tolerance=1e-8)[0]
    assert lin.u0.tolist() == [0.1]
    # At t = 0 the pendulum is upright (angle 0), so e = -r and force = kp e = -6.
    assert lin.y0 == pytest.approx([-6.0, 0.0], abs=1e-9)
    assert lin.x0.shape == (5,)
    # Units come from the coordinates (dx -> m, ay -> rad) and their rates; xi has none.
    assert lin.state_units == ["m", "rad", "m/s", "rad/s", ""]
    assert lin.input_units == ["rad"] and lin.output_units == ["N", "rad"]


def test_continue_a_host_simulation_then_linearize_the_instance(packed, tmp_path):
    # The fmpy flow: simulate_fmu(..., terminate=False, fmu_instance=..., set_stop_time=False)
    # leaves the instance at its last communication point; linearize(instance) linearizes
    # there. The same communication points through mbfmu.linearize(path, step=...) give
    # the same numbers bit for bit.
    path = packed("double_pendulum")
    md = read_model_description(str(path))
    unzipdir = extract(str(path), unzipdir=str(tmp_path / "u"))
    inst = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier)
    inst.instantiate()
    simulate_fmu(
        unzipdir,
        stop_time=0.5,
        output_interval=0.05,
        relative_tolerance=1e-8,
        fmu_instance=inst,
        terminate=False,
        set_stop_time=False,
        model_description=md,
    )
    here = mbfmu.linearize(inst)[0]
    assert here.time == pytest.approx(0.5, abs=1e-12)
    later = mbfmu.linearize(inst, at=0.7, step=0.05)[0]
    assert later.time == pytest.approx(0.7, abs=1e-12)
    inst.terminate()
    inst.freeInstance()
    ref = mbfmu.linearize(path, at=[0.5, 0.7], tolerance=1e-8, step=0.05)
    assert np.array_equal(here.A, ref[0].A)
    assert np.max(np.abs(later.A - ref[1].A)) <= 1e-12 * np.max(np.abs(ref[1].A))


def test_without_set_stop_time_false_the_fmu_refuses_steps_past_the_stop_time(packed, tmp_path):
    # FMI 2.0: with a stop time defined in fmi2SetupExperiment, a doStep past it is an
    # error. simulate_fmu passes its stop_time unless set_stop_time=False (README).
    from fmpy.fmi1 import FMICallException

    path = packed("pendulum")
    md = read_model_description(str(path))
    unzipdir = extract(str(path), unzipdir=str(tmp_path / "u"))
    inst = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier)
    inst.instantiate()
    simulate_fmu(unzipdir, stop_time=0.2, output_interval=0.1, fmu_instance=inst, terminate=False, model_description=md)
    with pytest.raises(FMICallException):
        inst.doStep(0.2, 0.1)
    with pytest.raises(mbfmu.FMUCallError, match="fmi2DoStep"):
        mbfmu.linearize(inst, at=0.3)
    assert mbfmu.linearize(inst)[0].time == pytest.approx(0.2, abs=1e-12)
    inst.terminate()
    inst.freeInstance()


def test_cli_input_file_and_package_inputs_give_the_same_linearization(packed, tmp_path):
    # A reference ramp r(t) on the PID cart-pendulum: `mbfmu linearize --input` (engine
    # called directly) and mbfmu.linearize(inputs=...) (fmpy sets values and slopes at
    # the rows) follow the same piecewise-linear signal: same A, B, C, D (1e-9) at a
    # moving point, and the operating point's r is the interpolated value.
    rows = [(0.0, 0.0), (0.4, 0.2), (1.0, -0.1)]
    csv = tmp_path / "r.csv"
    csv.write_text("time,r\n" + "".join(f"{t!r},{r!r}\n" for t, r in rows))
    out = tmp_path / "lin.json"
    cli_linearize(MODELS / "cart_pendulum_pid.xml", [0.7], 1e-9, out, "--input", str(csv))
    (ref,) = mbfmu.load(out)
    sig = np.array(rows, dtype=[("time", float), ("r", float)])
    (lin,) = mbfmu.linearize(packed("cart_pendulum_pid"), at=0.7, inputs=sig, tolerance=1e-9)
    assert lin.u0[0] == pytest.approx(0.2 - 0.3 * 0.5, abs=1e-15)
    assert abs(lin.x0[1]) > 1e-3  # the pendulum moved: a moving point
    for k in "ABCD":
        want = getattr(ref, k)
        assert np.max(np.abs(getattr(lin, k) - want)) <= 1e-9 * max(1.0, np.max(np.abs(want))), k
