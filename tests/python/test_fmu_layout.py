"""The linearization states are selected once, when the FMU is packed, and carried in
resources/states.txt: an instance reads them (a missing or foreign file is an
fmi2Instantiate failure with a logged reason), and a model whose states cannot be selected
is packed with a warning that says why."""

import shutil

import pytest
from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave

import mbfmu
from fmu_helpers import MODELS, LogCapture, pack_model


def instantiate(p, unzipped, log):
    s = FMU2Slave(
        guid=p.md.guid,
        unzipDirectory=str(unzipped),
        modelIdentifier=p.md.coSimulation.modelIdentifier,
        instanceName="layout",
    )
    s.instantiate(callbacks=log.callbacks)
    return s


def test_a_missing_or_foreign_state_layout_fails_instantiation_with_the_reason_logged(tmp_path):
    p = pack_model(MODELS / "pendulum.xml", tmp_path)
    layout = p.unzipped / "resources" / "states.txt"
    assert layout.read_text().startswith("mbfmu state layout 1\nguid\t" + p.md.guid + "\n")
    log = LogCapture()
    instantiate(p, p.unzipped, log).freeInstance()
    assert not log.records

    other = pack_model(MODELS / "double_pendulum.xml", tmp_path)
    for name, change, reason in [
        ("missing", lambda d: (d / "resources" / "states.txt").unlink(), "cannot read"),
        (
            "foreign",
            lambda d: shutil.copy(other.unzipped / "resources" / "states.txt", d / "resources"),
            "belongs to the model of GUID " + other.md.guid,
        ),
    ]:
        d = tmp_path / name
        shutil.copytree(p.unzipped, d)
        change(d)
        log = LogCapture()
        with pytest.raises(Exception, match="[Ff]ailed to instantiate"):
            instantiate(p, d, log)
        messages = log.messages()
        assert len(messages) == 1 and messages[0].startswith("fmi2Instantiate: "), log.records
        assert "states.txt" in messages[0] and reason in messages[0], messages[0]


def test_a_model_that_cannot_be_assembled_packs_with_a_located_warning(tmp_path):
    text = (
        (MODELS / "fourbar.xml").read_text().replace('<parameter name="a" value="0.2"', '<parameter name="a" value="5"')
    )
    model = tmp_path / "fourbar_long.xml"
    model.write_text(text)
    located = r"no linearization states.*fourbar_long\.xml:\d+:\d+: joint 'rocker_pin'"
    with pytest.warns(mbfmu.PackWarning, match=located):
        fmu = mbfmu.pack(model, tmp_path / "fourbar_long.fmu")
    md = read_model_description(str(fmu))
    assert md.derivatives == []


def test_packing_a_model_with_states_warns_nothing(tmp_path, recwarn):
    mbfmu.pack(MODELS / "chaplygin_sleigh.xml", tmp_path / "sleigh.fmu")
    assert not [w for w in recwarn if issubclass(w.category, mbfmu.PackWarning)]
