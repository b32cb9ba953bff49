"""Shared fixtures of the Python tests: FMUs packed once per session."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from fmu_helpers import MODELS, Packed, pack_model  # noqa: E402

# A free rotor: one body turning about ground z on a revolute joint, driven by the input
# torque T about z (no gravity, no other force). J_zz = J, so J dw/dt = T(t) exactly:
# T constant gives w = T t / J; T(t) = T + s t gives w = (T t + s t^2 / 2) / J.
ROTOR = """<?xml version="1.0" encoding="UTF-8"?>
<!-- Free rotor driven by the input torque T about ground z: J w' = T. -->
<multibody name="rotor" version="1">
  <parameter name="J" value="0.5" unit="kg.m2" description="moment of inertia about the axis"/>
  <ground>
    <marker name="O" position="0 0 0"/>
  </ground>
  <body name="r" mass="2" inertia="1, 1, J" position="0 0 0">
    <marker name="axis" position="0 0 0"/>
  </body>
  <joint name="bearing" type="revolute" i="r.axis" j="ground.O"/>
  <input name="T" unit="N.m"/>
  <gforce name="drive" i="r.cm" torque="0 0 T"/>
  <output name="w" function="wz(r.cm)" unit="rad/s"/>
  <output name="angle" function="az(r.cm, ground.O)" unit="rad"/>
  <experiment start="0" stop="1" step="0.01" tolerance="1e-8"/>
</multibody>
"""


@pytest.fixture(scope="session")
def packed(tmp_path_factory):
    """packed(name) -> Packed: models/<name>.xml packed once (zip and unzipped); `name` may
    name a subdirectory (`flexible/suspension`)."""
    cache: dict[str, Packed] = {}

    def get(name: str) -> Packed:
        if name not in cache:
            cache[name] = pack_model(MODELS / f"{name}.xml", tmp_path_factory.mktemp(name.replace("/", "-")))
        return cache[name]

    return get


@pytest.fixture(scope="session")
def rotor(tmp_path_factory) -> Packed:
    """The input-driven rotor model (ROTOR), written to a temporary directory and packed."""
    d = tmp_path_factory.mktemp("rotor")
    model = d / "rotor.xml"
    model.write_text(ROTOR)
    return pack_model(model, d)
