"""Benchmark (not a test): the N-link chain of bench/chain_model.sh for 1 s in mbfmu,
Exudyn and MuJoCo, side by side (run through bench/peers/run.sh).

For each N: mbfmu's assembled start pose (`--set j1.angle=0.5 --set j2.angle=0.5`) is read
back as all N joint angles and given to the peers; a tight mbfmu reference (tol 1e-10,
10 ms samples, cached in the work directory) gives the tip error. The runs, interleaved
round by round so that the machine's load falls on all alike, median of REPEATS:
  mbfmu FMU   fmpy FMU2Slave, 1000 x doStep(t, 1 ms), tol 1e-4 (only the loop timed)
  mbfmu CLI   `mbfmu simulate --end 1 --step 0.001 --tol 1e-4` (the whole process)
  Exudyn      rigid bodies + revolute joints, generalized-alpha, h = 1 ms, sparse solver
  MuJoCo      joint coordinates, RK4, dt = 1 ms, mj_step(nstep=1000)
then once each: mbfmu CLI at the extra tolerances, and the verification runs (MuJoCo RK4
at 0.1 ms; Exudyn at 0.1 ms for N <= 100).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import statistics
import sys
import warnings
from pathlib import Path

import numpy as np

import engines
from chain import Chain

warnings.filterwarnings("ignore", category=DeprecationWarning)


def digest(*parts: bytes) -> str:
    h = hashlib.sha256()
    for p in parts:
        h.update(p)
    return h.hexdigest()[:16]


def reference(binary: str, model: Path, work: Path, tol: float) -> engines.Run:
    """The tight mbfmu run (10 ms samples), cached by binary, model and tolerance."""
    key = digest(Path(binary).read_bytes(), model.read_bytes(), repr(tol).encode())
    cache = work / f"ref_{model.stem}_{key}.npz"
    if cache.exists():
        d = np.load(cache)
        return engines.Run(float(d["wall"]), float(d["cpu"]), int(d["steps"]), d["t"], d["tip"])
    print(f"  reference: mbfmu simulate {model.name} --tol {tol:g} --step 0.01 ...", file=sys.stderr, flush=True)
    r = engines.mbfmu_cli(binary, str(model), tol=tol, step=0.01)
    np.savez(cache, wall=r.wall, cpu=r.cpu, steps=r.steps, t=r.t, tip=r.tip)
    return r


def errors(run: engines.Run, ref: engines.Run) -> tuple[float, float]:
    """|tip - tip_ref| at t = 1 s, and its largest value at the reference's 10 ms samples."""
    end = float(ref.t[-1])
    e_end = float(np.linalg.norm(run.tip_at(end) - ref.tip_at(end)))
    e_max = max(float(np.linalg.norm(run.tip_at(t) - ref.tip_at(t))) for t in ref.t)
    return e_end, e_max


def row_text(row: tuple) -> str:
    n, label, wall, us, e_end, e_max, r_fmu, r_cli, note = row
    return (
        f"{n:>4}  {label:<38} {wall:>9.3f} {us:>9.1f} {e_end:>11.2e} {e_max:>9.2e} {r_fmu:>7.3f} {r_cli:>7.3f}  {note}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sizes", nargs="*", type=int, default=[10, 100, 300])
    ap.add_argument("--mbfmu", required=True, help="the mbfmu executable")
    ap.add_argument("--work", required=True, type=Path, help="models, FMUs, cached references (from run.sh)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--tol", type=float, default=1e-4)
    ap.add_argument("--extra-tols", default="1e-5,1e-6", help="comma-separated, may be empty")
    ap.add_argument("--ref-tol", type=float, default=1e-10)
    ap.add_argument("--verify-max-n", type=int, default=100, help="MuJoCo at 0.1 ms only up to this N")
    ap.add_argument("--verify-exudyn-max-n", type=int, default=10, help="Exudyn at 0.1 ms only up to this N")
    args = ap.parse_args()
    args.work = args.work.resolve()
    if Path(args.mbfmu).exists():
        args.mbfmu = str(Path(args.mbfmu).resolve())
    os.chdir(args.work)  # MuJoCo writes MUJOCO_LOG.TXT into the working directory
    h = 1e-3
    extra_tols = [float(x) for x in args.extra_tols.split(",") if x.strip()]

    rows: list[tuple] = []
    checks: list[str] = []
    for n in args.sizes:
        model, pose_model, fmu = (args.work / f"chain{n}{s}" for s in (".xml", "_pose.xml", ".fmu"))
        chain = Chain.load(n)
        theta, tip0 = engines.mbfmu_pose(args.mbfmu, str(pose_model))
        fk0 = chain.pose(theta)[3]
        ref = reference(args.mbfmu, model, args.work, args.ref_tol)
        checks.append(
            f"N={n}: start pose j1..j4 = {np.array2string(theta[:4], precision=6)}, "
            f"|j3..jN| up to {np.abs(theta[2:]).max() if n > 2 else 0:.3f} rad; "
            f"forward kinematics of the angles vs mbfmu's tip at t=0: {np.linalg.norm(fk0 - tip0):.1e} m; "
            f"reference (tol {args.ref_tol:g}) {ref.wall:.1f} s"
        )

        engines_timed = {
            "mbfmu FMU": lambda fmu=fmu: engines.mbfmu_fmu(str(fmu), tol=args.tol, step=h),
            "mbfmu CLI": lambda model=model: engines.mbfmu_cli(args.mbfmu, str(model), tol=args.tol, step=h),
            "Exudyn": lambda chain=chain, theta=theta: engines.exudyn_run(chain, theta, h=h),
            "MuJoCo": lambda chain=chain, theta=theta: engines.mujoco_run(chain, theta, dt=h),
        }
        runs: dict[str, list[engines.Run]] = {k: [] for k in engines_timed}
        for rnd in range(args.repeats):
            for name, fn in engines_timed.items():
                print(f"  N={n} round {rnd + 1}/{args.repeats}: {name} ...", file=sys.stderr, flush=True)
                runs[name].append(fn())
        med = {k: statistics.median(r.wall for r in v) for k, v in runs.items()}
        labels = {
            "mbfmu FMU": f"mbfmu FMU doStep 1 ms, tol {args.tol:g}",
            "mbfmu CLI": f"mbfmu simulate --step 1 ms, tol {args.tol:g}",
            "Exudyn": "Exudyn gen-alpha h=1 ms, sparse",
            "MuJoCo": "MuJoCo RK4 dt=1 ms",
        }
        for name, rs in runs.items():
            e_end, e_max = errors(rs[0], ref)
            extra = f"init {rs[0].extra['init_s']:.3f} s" if "init_s" in rs[0].extra else rs[0].extra.get("note", "")
            ratio = (med[name] / med["mbfmu FMU"], med[name] / med["mbfmu CLI"])
            rows.append((n, labels[name], med[name], 1e6 * med[name] / rs[0].steps, e_end, e_max, *ratio, extra))
        for tol in extra_tols:
            print(f"  N={n}: mbfmu CLI tol {tol:g} ...", file=sys.stderr, flush=True)
            r = engines.mbfmu_cli(args.mbfmu, str(model), tol=tol, step=h)
            e_end, e_max = errors(r, ref)
            ratio = (r.wall / med["mbfmu FMU"], r.wall / med["mbfmu CLI"])
            rows.append(
                (
                    n,
                    f"mbfmu simulate --step 1 ms, tol {tol:g}",
                    r.wall,
                    1e6 * r.wall / r.steps,
                    e_end,
                    e_max,
                    *ratio,
                    "1 run",
                )
            )

        for row in rows[-(len(runs) + len(extra_tols)) :]:  # as measured, in case a later N fails
            print("  " + row_text(row), file=sys.stderr, flush=True)

        # Verification: the peers converge to the mbfmu reference (same model, pose, signs).
        print(f"  N={n}: verification runs ...", file=sys.stderr, flush=True)
        ver = []
        if n <= args.verify_max_n:
            ver.append(("MuJoCo RK4 dt=0.1 ms", engines.mujoco_run(chain, theta, dt=1e-4)))
        if n <= args.verify_exudyn_max_n:
            ver.append(("Exudyn gen-alpha h=0.1 ms", engines.exudyn_run(chain, theta, h=1e-4, sample=1e-2)))
        for label, r in ver:
            e_end, e_max = errors(r, ref)
            e0 = float(np.linalg.norm(r.tip_at(0.0) - ref.tip_at(0.0)))
            checks.append(
                f"N={n}: {label} vs reference: tip error at t=0 {e0:.1e} m, at 1 s {e_end:.2e} m, "
                f"max over 1 s (10 ms samples) {e_max:.2e} m ({r.wall:.1f} s)"
            )
        for name in ("Exudyn", "MuJoCo", "mbfmu FMU"):
            e0 = float(np.linalg.norm(runs[name][0].tip_at(0.0) - ref.tip_at(0.0)))
            checks.append(f"N={n}: {name} 1 ms: tip at t=0 vs reference {e0:.1e} m")

    print()
    print("The N-link chain (bench/chain_model.sh), 1 s from j1 = j2 = 0.5 rad; wall times are medians")
    print(f"of {args.repeats} runs; tip error = |tip of link N - mbfmu reference (tol {args.ref_tol:g})|.")
    print("ratio = engine's time / mbfmu's time (> 1: mbfmu faster), against the FMU loop and the CLI.")
    print()
    head = (
        f"{'N':>4}  {'engine':<38} {'wall [s]':>9} {'us/step':>9} {'tip err 1 s':>11} "
        f"{'max err':>9} {'/FMU':>7} {'/CLI':>7}  note"
    )
    print(head)
    print("-" * len(head))
    for row in rows:
        print(row_text(row))
    print()
    print("Checks (same model, same start pose and sign convention in every engine):")
    for c in checks:
        print("  " + c)


if __name__ == "__main__":
    main()
