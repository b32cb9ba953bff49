"""The N-link chain of bench/chain_model.sh, for mbfmu and its peers (Exudyn, MuJoCo).

The geometry is read from the model file that bench/chain_model.sh writes, so every engine
gets exactly that model: link k (mass, inertia, marker 'top' at the joint above it, marker
'tip' at the joint below it, joint axis = the z axis of 'top', in body axes; every body
drawn with identity orientation).

Joint angle convention (mbfmu, MODEL_FORMAT.md): `jk.angle` = az(lk.top, parent.tip), the
right-handed rotation of marker i about z_j. Both markers are drawn with the same axes, so
R_k = R_{k-1} · Rot(a_k, theta_k), with a_k the joint axis in body axes (x for odd k, y for
even k) and R_0 = I. MuJoCo's hinge (child rotated about its axis in the child frame by
qpos) and Exudyn's bodies placed by this forward kinematics use the same convention.

    python chain.py model N     # the model with outputs tip_x, tip_y (tip_z is there)
    python chain.py pose N      # the model with outputs a1..aN = the joint angles
    python chain.py sets        # the start pose as mbfmu arguments: --set j1.angle=0.5 ...
"""

from __future__ import annotations

import subprocess
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

BENCH = Path(__file__).resolve().parent.parent
G = 9.80665
# The swing pose of the benchmark: `--set` pairs given to mbfmu simulate and pack.
POSE = {"j1.angle": 0.5, "j2.angle": 0.5}


def chain_xml(n: int) -> str:
    """bench/chain_model.sh N, as written."""
    return subprocess.run([str(BENCH / "chain_model.sh"), str(n)], check=True, capture_output=True, text=True).stdout


def _with_outputs(xml: str, outputs: list[tuple[str, str]]) -> str:
    extra = "".join(f'  <output name="{name}" function="{fn}" unit="{unit}"/>\n' for name, fn, unit in outputs)
    assert xml.count("</multibody>") == 1
    return xml.replace("</multibody>", extra + "</multibody>")


def model_xml(n: int) -> str:
    """The chain with the tip's x and y as outputs too (tip_z = dz(lN.tip) is the model's)."""
    return _with_outputs(chain_xml(n), [("tip_x", f"dx(l{n}.tip)", "m"), ("tip_y", f"dy(l{n}.tip)", "m")])


def pose_xml(n: int) -> str:
    """The chain with every joint angle as an output: a_k = az(lk.top, parent.tip)."""
    outs = [("tip_x", f"dx(l{n}.tip)", "m"), ("tip_y", f"dy(l{n}.tip)", "m")]
    for k in range(1, n + 1):
        parent = "ground.O" if k == 1 else f"l{k - 1}.tip"
        outs.append((f"a{k}", f"az(l{k}.top, {parent})", "rad"))
    return _with_outputs(chain_xml(n), outs)


def _vec(s: str) -> np.ndarray:
    return np.array([float(x) for x in s.split()])


@dataclass
class Chain:
    """Link data in body axes (the body frame is the centre-of-mass frame)."""

    mass: np.ndarray  # (N,)
    inertia: np.ndarray  # (N, 3): principal moments (the model's inertia is diagonal)
    top: np.ndarray  # (N, 3): marker 'top' (joint above) relative to the CM
    tip: np.ndarray  # (N, 3): marker 'tip' (joint below) relative to the CM
    axis: np.ndarray  # (N, 3): joint k's axis (z of 'top')
    cm0: np.ndarray  # (N, 3): drawn CM positions

    @property
    def n(self) -> int:
        return len(self.mass)

    @classmethod
    def from_xml(cls, xml: str) -> Chain:
        root = ET.fromstring(xml)
        grav = _vec(root.find("gravity").get("value"))
        assert np.allclose(grav, [0, 0, -G]), grav
        mass, inertia, top, tip, axis, tip_axis, cm0 = [], [], [], [], [], [], []
        for b in root.findall("body"):
            assert b.get("euler313") is None and b.get("z_axis") is None, "bodies are drawn unrotated"
            mass.append(float(b.get("mass")))
            inertia.append(_vec(b.get("inertia")))
            cm0.append(_vec(b.get("position")))
            markers = {m.get("name"): m for m in b.findall("marker")}
            top.append(_vec(markers["top"].get("position")))
            tip.append(_vec(markers["tip"].get("position")))
            axis.append(_vec(markers["top"].get("z_axis")))
            tip_axis.append(_vec(markers["tip"].get("z_axis")))
        # each joint's two markers are drawn with the same axes (so the angle starts at 0)
        assert all(np.array_equal(a, b) for a, b in zip(axis[1:], tip_axis[:-1], strict=True))
        ground_o = root.find("ground").find("marker")
        assert np.array_equal(axis[0], _vec(ground_o.get("z_axis"))) and not _vec(ground_o.get("position")).any()
        inertia = np.array(inertia)
        assert inertia.shape[1] == 3, "diagonal inertia expected"
        return cls(np.array(mass), inertia, np.array(top), np.array(tip), np.array(axis), np.array(cm0))

    @classmethod
    def load(cls, n: int) -> Chain:
        return cls.from_xml(chain_xml(n))

    def pose(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Forward kinematics at joint angles theta: (R (N,3,3), pivots (N,3), CMs (N,3), tip of link N)."""
        rot = np.empty((self.n, 3, 3))
        piv = np.empty((self.n, 3))
        cm = np.empty((self.n, 3))
        r = np.eye(3)
        p = np.zeros(3)  # joint 1 sits at the ground origin
        for k in range(self.n):
            r = r @ axis_rotation(self.axis[k], theta[k])
            rot[k], piv[k] = r, p
            cm[k] = p - r @ self.top[k]
            p = cm[k] + r @ self.tip[k]
        return rot, piv, cm, p


def axis_rotation(a: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix by angle about the unit axis a (right-handed)."""
    a = np.asarray(a, float) / np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)


def set_args() -> list[str]:
    """The start pose as mbfmu's `--set NAME=VALUE` arguments."""
    return [a for name, value in POSE.items() for a in ("--set", f"{name}={value!r}")]


def main() -> None:
    if sys.argv[1] == "sets":
        print(" ".join(set_args()))
        return
    what, n = sys.argv[1], int(sys.argv[2])
    sys.stdout.write({"model": model_xml, "pose": pose_xml}[what](n))


if __name__ == "__main__":
    main()
