"""Benchmark (not a test): linearization + all eigenvalues of the N-link chain of
bench/chain_model.sh hanging at rest (`chain_model.sh N hanging`), mbfmu against Exudyn's
minimal-coordinate kinematic tree, side by side (run through bench/peers/lineig.sh).

For each N, the runs interleaved round by round (the machine's load falls on all alike),
medians of REPEATS:
  mbfmu full    `mbfmu linearize hangN.xml --at 0 --format json --out X.json`, the whole
                process (parse, assembly, A B C D, all 2N eigenvalues, the JSON with the
                matrices); the eigenvalues are read from the JSON's "eigenvalues"
  mbfmu table   the same with the default `--format table` (eigenvalues only, no matrices
                written): how much of "full" is the JSON
  mbfmu modes   `mbfmu linearize ... --modes K` (default 10, shift-invert Arnoldi), whole process
  Exudyn        in-process: build = ObjectKinematicTree (a revolute joint per link, N
                minimal coordinates) + Assemble; lin+eig = mbs.ComputeODE2Eigenvalues()
                (it computes M and K = -df/dq itself, then all N eigenvalues omega^2 of the
                symmetric pencil by scipy's dense eigh); lin = mbs.ComputeLinearizedSystem()
                (M, K, D alone), timed after lin+eig, for where the time goes
Not timed: Python's and scipy's imports (done before), reading the model XML into numpy.
lineig.sh sets OPENBLAS_NUM_THREADS=1 unless given: scipy's eigh with 2 OpenBLAS threads on
the shared 2-core machine slows down up to 90-fold whenever anything else runs.

The check: the lowest K frequencies (positive imaginary parts of mbfmu's eigenvalues, sorted;
Exudyn's sqrt(omega^2)) agree to about 1e-9 relative; a difference above 1e-7 is flagged.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from chain import BENCH, Chain, G

warnings.filterwarnings("ignore", category=DeprecationWarning)
AGREE = 1e-7  # a larger relative frequency difference means the two models differ


def hanging_xml(n: int) -> str:
    """bench/chain_model.sh N hanging, as written."""
    cmd = [str(BENCH / "chain_model.sh"), str(n), "hanging"]
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def mbfmu_linearize(binary: str, model: Path, out: Path | None, *extra: str) -> tuple[float, np.ndarray | None]:
    """`mbfmu linearize model --at 0 [--format json --out out] extra...`, timed as a process;
    the eigenvalues (complex) from the JSON if out is given."""
    cmd = [binary, "linearize", str(model), "--at", "0", *extra]
    if out is not None:
        cmd += ["--format", "json", "--out", str(out)]
    t0 = time.perf_counter()
    res = subprocess.run(cmd, check=False, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if res.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: exit {res.returncode}: {res.stderr.strip()}")
    if out is None:
        return wall, None
    (at0,) = json.loads(out.read_text())  # one operating time
    ev = np.array(at0["eigenvalues"], dtype=float)
    return wall, ev[:, 0] + 1j * ev[:, 1]


def frequencies(ev: np.ndarray) -> np.ndarray:
    """The undamped frequencies [rad/s] of a conservative system's eigenvalues +-i omega, sorted."""
    return np.sort(ev.imag[ev.imag > 0])


def exudyn_tree(chain: Chain):
    """The chain as one ObjectKinematicTree: joint k's frame sits at joint k with the body's
    (drawn) axes, so q = 0 is the drawn pose; link k rotates about its drawn axis (RevoluteX
    or RevoluteY), its joint offset from joint k-1 is tip - top of link k-1, its CM is at
    -top. Returns (SystemContainer, MainSystem), assembled; keep both alive."""
    import exudyn as exu
    from exudyn.utilities import NodeGenericODE2, ObjectKinematicTree

    types = {0: exu.JointType.RevoluteX, 1: exu.JointType.RevoluteY, 2: exu.JointType.RevoluteZ}
    joint_types = []
    for a in chain.axis:
        i = int(np.argmax(np.abs(a)))
        assert a[i] == 1 and np.count_nonzero(a) == 1, f"joint axis {a} is not a body axis"
        joint_types.append(types[i])
    n = chain.n
    offsets, transforms, inertias, coms = exu.Vector3DList(), exu.Matrix3DList(), exu.Matrix3DList(), exu.Vector3DList()
    for k in range(n):
        offsets.Append(np.zeros(3) if k == 0 else chain.tip[k - 1] - chain.top[k - 1])
        transforms.Append(np.eye(3))
        inertias.Append(np.diag(chain.inertia[k]))
        coms.Append(-chain.top[k])
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    zeros = [0.0] * n
    node = mbs.AddNode(
        NodeGenericODE2(
            numberOfODE2Coordinates=n,
            referenceCoordinates=zeros,
            initialCoordinates=zeros,
            initialCoordinates_t=zeros,
        )
    )
    mbs.AddObject(
        ObjectKinematicTree(
            nodeNumber=node,
            jointTypes=joint_types,
            linkParents=list(range(-1, n - 1)),
            jointTransformations=transforms,
            jointOffsets=offsets,
            linkInertiasCOM=inertias,
            linkCOMs=coms,
            linkMasses=list(chain.mass),
            gravity=[0.0, 0.0, -G],
        )
    )
    mbs.Assemble()
    return sc, mbs


def exudyn_lineig(chain: Chain) -> dict:
    """Build (timed), lin+eig (timed), then lin alone (timed); the frequencies [rad/s]."""
    t0 = time.perf_counter()
    sc, mbs = exudyn_tree(chain)
    t1 = time.perf_counter()
    omega2, _ = mbs.ComputeODE2Eigenvalues(useAbsoluteValues=False)  # all N, dense eigh
    t2 = time.perf_counter()
    mbs.ComputeLinearizedSystem()  # [M, K, D]
    t3 = time.perf_counter()
    del sc
    assert omega2.min() > 0, f"not a stable equilibrium: omega^2 = {omega2.min()}"
    return {"build": t1 - t0, "eig": t2 - t1, "lin": t3 - t2, "omega": np.sqrt(np.sort(omega2))}


def rel_diff(a: np.ndarray, ref: np.ndarray, k: int) -> float:
    """The largest |a - ref| / ref over the lowest k values."""
    k = min(k, len(a), len(ref))
    return float(np.max(np.abs(a[:k] - ref[:k]) / ref[:k]))


HEAD = (
    f"{'N':>5} {'mbfmu full':>10} {'Exudyn':>8} {'Exu/mbf':>7} {'modes':>7} {'rel diff':>8}"
    f" {'mbf table':>9} {'Exu build':>9} {'Exu lin':>8} {'Exu total':>9} {'modes diff':>10} {'all diff':>8}"
)
UNITS = (
    f"{'':>5} {'[s]':>10} {'lin+eig':>8} {'':>7} {'[s]':>7} {'lowest':>8}"
    f" {'[s]':>9} {'[s]':>9} {'M,K,D':>8} {'[s]':>9} {'lowest':>10} {'freqs':>8}"
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sizes", nargs="*", type=int, default=[10, 300, 1000])
    ap.add_argument("--mbfmu", required=True, help="the mbfmu executable")
    ap.add_argument("--work", required=True, type=Path, help="where the models go (hangN.xml)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--modes", type=int, default=10, help="K of `linearize --modes K` and of the check; 0: no --modes")
    args = ap.parse_args()
    k = args.modes if args.modes > 0 else 10

    import exudyn
    import scipy
    import scipy.linalg  # noqa: F401  (Exudyn imports these in ComputeODE2Eigenvalues: not timed)
    import scipy.sparse  # noqa: F401
    import scipy.sparse.linalg  # noqa: F401

    blas = os.environ.get("OPENBLAS_NUM_THREADS", "default")
    print(f"lineig: exudyn {exudyn.__version__}, scipy {scipy.__version__}, numpy {np.__version__}", end="")
    print(f" (OPENBLAS_NUM_THREADS={blas}); {args.mbfmu}")
    print(f"medians of {args.repeats}; ratio Exu/mbf = Exudyn lin+eig / mbfmu full (> 1: mbfmu faster);")
    print(f"rel diff = max relative difference of the lowest {k} frequencies, Exudyn vs mbfmu full")
    print(HEAD)
    print(UNITS, flush=True)
    args.work.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="lineig") as tmp:
        out = Path(tmp) / "lin.json"
        for n in args.sizes:
            xml = hanging_xml(n)
            model = args.work / f"hang{n}.xml"
            model.write_text(xml)
            chain = Chain.from_xml(xml)
            full, table, modes, exu = [], [], [], []
            w_full = w_modes = None
            for _ in range(args.repeats):
                wall, ev = mbfmu_linearize(args.mbfmu, model, out)
                full.append(wall)
                w_full = frequencies(ev)
                assert len(w_full) == n, f"mbfmu: {len(w_full)} positive frequencies, N = {n}"
                table.append(mbfmu_linearize(args.mbfmu, model, None)[0])
                if args.modes > 0:
                    wall, ev = mbfmu_linearize(args.mbfmu, model, out, "--modes", str(args.modes))
                    modes.append(wall)
                    w_modes = frequencies(ev)
                exu.append(exudyn_lineig(chain))
            med = statistics.median
            w_exu = exu[-1]["omega"]
            eig = med(r["eig"] for r in exu)
            diff = rel_diff(w_exu, w_full, k)
            cells = [
                f"{n:>5}",
                f"{med(full):>10.4f}",
                f"{eig:>8.4f}",
                f"{eig / med(full):>7.3f}",
                f"{med(modes):>7.4f}" if modes else f"{'-':>7}",
                f"{diff:>8.1e}",
                f"{med(table):>9.4f}",
                f"{med(r['build'] for r in exu):>9.4f}",
                f"{med(r['lin'] for r in exu):>8.4f}",
                f"{med(r['build'] + r['eig'] for r in exu):>9.4f}",
                f"{rel_diff(w_modes, w_exu, k):>10.1e}" if w_modes is not None else f"{'-':>10}",
                f"{rel_diff(w_exu, w_full, n):>8.1e}",
            ]
            note = "  MODELS DIFFER" if diff > AGREE else ""
            print(" ".join(cells) + note, flush=True)
            if diff > AGREE:
                print(f"  lowest mbfmu: {w_full[:k]}\n  lowest Exudyn: {w_exu[:k]}", file=sys.stderr)


if __name__ == "__main__":
    main()
