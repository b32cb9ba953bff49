"""Start values on states (issue 25): a 7-joint serial arm with random joint axes, packed
and started through fmpy at a random pose and speed set as `start_values` on its states.

References, computed here: the states read back what was set (to 1e-12: assembly meets
start values like exact joint ICs, polished to round-off), and the tool point equals
forward kinematics multiplied out with numpy (to 1e-12 m on an arm of about 2 m), its
velocity the numerical derivative of that forward kinematics along the set speeds
(central difference, step 1e-6: truncation ~1e-12, round-off ~1e-10; bound 1e-8).
"""

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException

from fmu_helpers import LogCapture, Packed, initialize, new_slave, run_mbfmu

N = 7


def rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def euler(e):
    return rz(e[0]) @ rx(e[1]) @ rz(e[2])


def fmt(v):
    return " ".join(repr(float(x)) for x in v)


def arm(seed=7):
    """Joint frames (position, euler313 on the parent), child offsets (c, euler313)."""
    rng = np.random.default_rng(seed)
    links = []
    for _ in range(N):
        p = rng.uniform(-0.15, 0.15, 3) + np.array([0.0, 0.0, 0.25])
        links.append(
            (
                p,
                rng.uniform([-np.pi, 0, -np.pi], [np.pi, np.pi, np.pi]),
                rng.uniform(-0.15, 0.15, 3),
                rng.uniform([-np.pi, 0, -np.pi], [np.pi, np.pi, np.pi]),
            )
        )
    return links


def forward(links, q):
    """Ground poses of the bodies at joint angles q, and the tool point (body 6's origin)."""
    r, a = np.zeros(3), np.eye(3)
    poses = []
    for (p, pe, c, ce), th in zip(links, q, strict=True):
        joint = a @ euler(pe)
        origin = r + a @ p
        moving = joint @ rz(th)
        r = origin + moving @ c
        a = moving @ euler(ce)
        poses.append((r, a))
    return poses


def model(links):
    poses = forward(links, np.zeros(N))
    s = '<multibody name="arm7" version="1">\n<ground>\n'
    s += f'<marker name="J0" position="{fmt(links[0][0])}" euler313="{fmt(links[0][1])}"/>\n</ground>\n'
    for k, (r, a) in enumerate(poses):
        s += (
            f'<body name="b{k}" mass="{3.0 - 0.3 * k}" inertia="0.05 0.04 0.03" position="{fmt(r)}" '
            f'z_axis="{fmt(a[:, 2])}" x_axis="{fmt(a[:, 0])}">\n'
        )
        _, _, c, ce = links[k]
        ct = euler(ce).T
        s += f'<marker name="I" position="{fmt(-ct @ c)}" euler313="{fmt([-ce[2], -ce[1], -ce[0]])}"/>\n'
        if k + 1 < N:
            s += f'<marker name="J" position="{fmt(links[k + 1][0])}" euler313="{fmt(links[k + 1][1])}"/>\n'
        s += "</body>\n"
    for k in range(N):
        j = "ground.J0" if k == 0 else f"b{k - 1}.J"
        s += f'<joint name="q{k}" type="revolute" i="b{k}.I" j="{j}"/>\n'
    for c in "xyz":
        s += f'<output name="tool_{c}" function="d{c}(b6.cm)" unit="m"/>\n'
        s += f'<output name="tool_v{c}" function="v{c}(b6.cm)" unit="m/s"/>\n'
    return s + '<gravity value="0 0 -9.81"/>\n</multibody>\n'


@pytest.fixture(scope="module")
def arm_fmu(tmp_path_factory):
    d = tmp_path_factory.mktemp("arm7")
    links = arm()
    path = d / "arm7.xml"
    path.write_text(model(links))
    fmu = d / "arm7.fmu"
    r = run_mbfmu("pack", str(path), "-o", str(fmu))
    assert r.returncode == 0, r.stderr
    return links, fmu


def test_states_have_start_values_from_the_assembled_model(arm_fmu):
    _, fmu = arm_fmu
    md = read_model_description(str(fmu))
    by_name = {v.name: v for v in md.modelVariables}
    for k in range(N):
        s, w = by_name[f"q{k}.angle"], by_name[f"der(q{k}.angle)"]
        assert (s.initial, w.initial) == ("approx", "approx")
        # Drawn at zero angles and at rest.
        assert abs(float(s.start)) < 1e-9 and float(w.start) == 0.0


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_random_pose_and_speed_set_on_the_states_is_where_the_arm_starts(arm_fmu, seed):
    links, fmu = arm_fmu
    rng = np.random.default_rng(seed)
    q = rng.uniform(-2.5, 2.5, N)
    w = rng.uniform(-1.0, 1.0, N)
    start = {f"q{k}.angle": q[k] for k in range(N)}
    start.update({f"der(q{k}.angle)": w[k] for k in range(N)})
    names = [f"q{k}.angle" for k in range(N)] + [f"der(q{k}.angle)" for k in range(N)]
    tool = ["tool_x", "tool_y", "tool_z", "tool_vx", "tool_vy", "tool_vz"]
    res = simulate_fmu(str(fmu), stop_time=1e-3, output_interval=1e-3, start_values=start, output=names + tool)
    row = res[0]
    assert row["time"] == 0.0
    got = np.array([row[n] for n in names])
    np.testing.assert_allclose(got, np.concatenate([q, w]), rtol=0, atol=1e-12)
    expected = forward(links, q)[-1][0]
    np.testing.assert_allclose([row[n] for n in tool[:3]], expected, rtol=0, atol=1e-12)
    h = 1e-6
    v = (forward(links, q + h * w)[-1][0] - forward(links, q - h * w)[-1][0]) / (2 * h)
    np.testing.assert_allclose([row[n] for n in tool[3:]], v, rtol=0, atol=1e-8)


ROTOR_WITH_IC = """<multibody name="rotor_ic" version="1">
  <ground><marker name="O" position="0 0 0"/></ground>
  <body name="r" mass="2" inertia="1 1 0.5" position="0 0 0"><marker name="axis" position="0 0 0"/></body>
  <joint name="bearing" type="revolute" i="r.axis" j="ground.O" ic_angle="0.5"/>
</multibody>
"""


def test_start_values_that_cannot_hold_together_are_an_error_naming_them(tmp_path):
    # The joint's ic_angle asks for 0.5 rad, the start value set on its angle for 1.0: the
    # two cannot hold together. fmi2ExitInitializationMode fails (fmi2Error) with a message
    # naming the start value; the instance stays usable (fmi2Reset, then it starts).
    path = tmp_path / "rotor_ic.xml"
    path.write_text(ROTOR_WITH_IC)
    unz = tmp_path / "rotor_ic"
    r = run_mbfmu("pack", str(path), "-o", str(tmp_path / "rotor_ic.fmu"), "--out-dir", str(unz))
    assert r.returncode == 0, r.stderr
    p = Packed(path, tmp_path / "rotor_ic.fmu", unz, read_model_description(str(unz / "modelDescription.xml")))
    log = LogCapture()
    s = new_slave(p, log=log, logging_on=True)
    with pytest.raises(FMICallException):
        initialize(s, 1e-8, values={p.vr["bearing.angle"]: 1.0})
    text = " ".join(log.messages())
    assert "start value 'bearing.angle'" in text, text
    s.reset()
    initialize(s, 1e-8)
    assert abs(s.getReal([p.vr["bearing.angle"]])[0] - 0.5) < 1e-12
    s.terminate()
    s.freeInstance()
