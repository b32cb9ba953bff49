"""Precision-work diagram (benchmark, not a test): tip error at t = 1 s against CPU time
for the N-link chain (default N = 10 and 100), run through bench/peers/run.sh.

  mbfmu    free-running `mbfmu simulate --step 0.01 --tol E`, E = 1e-3 ... 1e-10
  Exudyn   generalized-alpha, fixed h = 10 ms ... 10 us (Exudyn's adaptiveStep only
           where the fixed step fails; marked)
  MuJoCo   RK4, dt = 10 ms ... 0.1 ms (a run MuJoCo finds unstable and resets is
           marked and left out of the plot)

A point predicted to take more than --limit seconds (from the series' previous points)
is skipped, and so is the rest of its series. The reference is MuJoCo RK4 at dt = 25 us
(independent of mbfmu, so that mbfmu's tight tolerances can be judged); its own error
is estimated from the run at 50 us (Richardson, RK4: |x(2h) - x(h)| / 15) and it is
compared with mbfmu's tol-1e-10 run. Writes the PNG (log-log) and prints the points.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from pathlib import Path

import numpy as np

import engines
from chain import Chain

warnings.filterwarnings("ignore", category=DeprecationWarning)

MBFMU_TOLS = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
EXUDYN_H = [1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5]
MUJOCO_DT = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4]
REF_DT = 2.5e-5


def predicted(times: list[float], grow: float | None) -> float:
    """A series' next CPU time: the last one times `grow` (fixed steps: the step ratio),
    or times the last growth factor (at least 1) when the work is not known in advance."""
    if not times:
        return 0.0
    if grow is not None:
        return times[-1] * grow
    return times[-1] * (max(1.0, times[-1] / times[-2]) if len(times) > 1 else 1.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sizes", nargs="*", type=int, default=[10, 100])
    ap.add_argument("--mbfmu", required=True)
    ap.add_argument("--work", required=True, type=Path)
    ap.add_argument("--limit", type=float, default=60.0, help="skip points predicted to take longer [s]")
    ap.add_argument("--png", type=Path, default=Path(__file__).with_name("precision_work.png"))
    args = ap.parse_args()
    args.work, args.png = args.work.resolve(), args.png.resolve()
    if Path(args.mbfmu).exists():
        args.mbfmu = str(Path(args.mbfmu).resolve())
    os.chdir(args.work)  # MuJoCo writes MUJOCO_LOG.TXT into the working directory

    points: dict[int, dict[str, list[tuple[str, float, float, str]]]] = {}
    notes: list[str] = []
    for n in args.sizes:
        model, pose_model = args.work / f"chain{n}.xml", args.work / f"chain{n}_pose.xml"
        chain = Chain.load(n)
        theta, _ = engines.mbfmu_pose(args.mbfmu, str(pose_model))
        print(f"  N={n}: reference MuJoCo RK4 dt={REF_DT:g} (and {2 * REF_DT:g}) ...", file=sys.stderr, flush=True)
        ref = engines.mujoco_run(chain, theta, dt=REF_DT, sample=None).tip_at(1.0)
        ref2 = engines.mujoco_run(chain, theta, dt=2 * REF_DT, sample=None).tip_at(1.0)
        pts: dict[str, list[tuple[str, float, float, str]]] = {"mbfmu": [], "Exudyn": [], "MuJoCo": []}

        def add(engine: str, setting: str, run: engines.Run, note: str = "", pts=pts, ref=ref, n=n) -> float:
            err = float(np.linalg.norm(run.tip_at(1.0) - ref))
            pts[engine].append((setting, run.cpu, err, note))
            print(f"  N={n} {engine} {setting}: cpu {run.cpu:.3f} s, error {err:.2e} m", file=sys.stderr, flush=True)
            return run.cpu

        times: list[float] = []
        for tol in MBFMU_TOLS:
            if predicted(times, None) > args.limit:
                notes.append(f"N={n}: mbfmu tol {tol:g} and tighter skipped (predicted > {args.limit:g} s)")
                break
            try:
                run = engines.mbfmu_cli(args.mbfmu, str(model), tol=tol, step=0.01, timeout=3 * args.limit)
            except Exception as e:  # a timeout or a failure ends the series, reported
                notes.append(f"N={n}: mbfmu tol {tol:g}: {str(e).splitlines()[0][:120]}")
                break
            times.append(add("mbfmu", f"tol {tol:g}", run))
            if tol == 1e-10:
                notes.append(
                    f"N={n}: mbfmu tol 1e-10 vs the reference: {pts['mbfmu'][-1][2]:.2e} m "
                    f"(the reference's own error estimate {np.linalg.norm(ref2 - ref) / 15:.1e} m)"
                )

        times = []
        for i, h in enumerate(EXUDYN_H):
            if predicted(times, EXUDYN_H[i - 1] / h if i else None) > args.limit:
                notes.append(f"N={n}: Exudyn h = {h:g} and smaller skipped (predicted > {args.limit:g} s)")
                break
            run = engines.exudyn_run(chain, theta, h=h, sample=0.1)
            times.append(add("Exudyn", f"h {h:g}", run, "adaptive" if "note" in run.extra else ""))
            if "note" in run.extra:
                notes.append(f"N={n}: Exudyn h = {h:g}: {run.extra['note']}")

        times = []
        for i, dt in enumerate(MUJOCO_DT):
            if predicted(times, MUJOCO_DT[i - 1] / dt if i else None) > args.limit:
                notes.append(f"N={n}: MuJoCo dt = {dt:g} and smaller skipped (predicted > {args.limit:g} s)")
                break
            run = engines.mujoco_run(chain, theta, dt=dt, sample=None)
            times.append(add("MuJoCo", f"dt {dt:g}", run, "unstable" if run.extra else ""))
        notes.append(
            f"N={n}: reference MuJoCo RK4 dt={REF_DT:g}, its error estimate |x(2h)-x(h)|/15 = "
            f"{np.linalg.norm(ref2 - ref) / 15:.1e} m"
        )
        points[n] = pts

    print()
    print("Precision-work: tip error at t = 1 s vs CPU time (the chain, 1 s from j1 = j2 = 0.5 rad)")
    print(f"{'N':>4}  {'engine':<7} {'setting':<12} {'CPU [s]':>9} {'tip error [m]':>14}  note")
    for n, pts in points.items():
        for engine, rows in pts.items():
            for setting, cpu, err, note in rows:
                print(f"{n:>4}  {engine:<7} {setting:<12} {cpu:>9.3f} {err:>14.2e}  {note}")
    print()
    for note in notes:
        print("  " + note)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(points), figsize=(6 * len(points), 4.8), squeeze=False)
    style = {"mbfmu": ("C0", "o"), "Exudyn": ("C1", "s"), "MuJoCo": ("C2", "^")}
    for ax, (n, pts) in zip(axes[0], points.items(), strict=True):
        for engine, rows in pts.items():
            ok = [(cpu, max(err, 1e-16), s) for s, cpu, err, note in rows if np.isfinite(err) and note != "unstable"]
            if not ok:
                continue
            color, marker = style[engine]
            ax.loglog([p[0] for p in ok], [p[1] for p in ok], marker=marker, color=color, label=engine)
            for cpu, err, s in ok:
                ax.annotate(s.split()[-1], (cpu, err), fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.set_title(f"{n}-link chain, 1 s")
        ax.set_xlabel("CPU time [s]")
        ax.set_ylabel("tip error at t = 1 s [m]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(args.png, dpi=120)
    print(f"\nwrote {args.png}")


if __name__ == "__main__":
    main()
