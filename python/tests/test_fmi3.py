"""The package on FMI 3.0 FMUs: `mbfmu.pack(..., fmi=3)` writes one, and `mbfmu.linearize`
of it (a path, or a host's fmpy FMU3Slave) equals the linearization of the same model's
FMI 2.0 FMU, itself checked against the CLI and analytic references in
test_linearize_mbfmu.py. Tolerance 1e-12 relative to the largest entry: the two FMUs run
one engine, bit for bit, and their derivatives come from one factorization of Eq. 34 by
different triangular solves (round-off ~1e-15)."""

import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest
from conftest import MODELS
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

import mbfmu
from mbfmu.errors import ArgumentError


def close(a, b) -> float:
    """Largest difference of A, B, C, D relative to 1 + the largest entry."""
    worst = 0.0
    for k in "ABCD":
        x, y = getattr(a, k), getattr(b, k)
        assert x.shape == y.shape, k
        if x.size:
            worst = max(worst, float(np.abs(x - y).max() / (1.0 + np.abs(y).max())))
    return worst


@pytest.mark.parametrize("name", ["double_pendulum", "cart_pendulum_pid", "benchmark_bicycle"])
def test_an_fmi3_fmu_linearizes_as_its_fmi2_twin(tmp_path, name):
    model = MODELS / f"{name}.xml"
    f2 = mbfmu.pack(model, tmp_path / f"{name}-2.fmu")
    f3 = mbfmu.pack(model, tmp_path / f"{name}-3.fmu", fmi=3)
    with zipfile.ZipFile(f3) as z:
        assert ET.fromstring(z.read("modelDescription.xml")).get("fmiVersion") == "3.0"
    at = [0.0, 0.25]
    for l2, l3 in zip(mbfmu.linearize(f2, at=at), mbfmu.linearize(f3, at=at), strict=True):
        assert l3.method == l2.method == "directional derivatives"
        assert l3.states == l2.states and l3.inputs == l2.inputs and l3.outputs == l2.outputs
        assert close(l3, l2) <= 1e-12, name


def test_a_host_fmi3_instance_is_linearized_where_it_stands(tmp_path):
    model = MODELS / "cart_pendulum_pid.xml"
    f3 = mbfmu.pack(model, tmp_path / "cart3.fmu", fmi=3)
    (reference,) = mbfmu.linearize(mbfmu.pack(model, tmp_path / "cart2.fmu"), at=0.1)
    md = read_model_description(str(f3))
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(f3)), modelIdentifier=md.coSimulation.modelIdentifier)
    fmu.instantiate()
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 0.1)
    (lin,) = mbfmu.linearize(fmu, at=None)
    assert lin.time == pytest.approx(0.1, abs=1e-15)
    assert close(lin, reference) <= 1e-12
    fmu.terminate()
    fmu.freeInstance()


def test_pack_refuses_an_unknown_fmi_version(tmp_path):
    with pytest.raises(ArgumentError, match="expected 2 or 3"):
        mbfmu.pack(MODELS / "pendulum.xml", tmp_path / "p.fmu", fmi=4)
