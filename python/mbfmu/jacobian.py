"""[A B; C D] from an FMU, column by column, skipping declared structural zeros.

Exact path: `fmi2GetDirectionalDerivative` with seeds grouped so that columns sharing no
nonzero row are seeded together (Curtis–Powell–Reid compression; each row of a group's
answer then belongs to exactly one column, so the result is the same numbers as unit
seeds). Unknowns that are states themselves get their unit row without a call.

Fallback: central differences of a map knowns -> unknowns, step h_j = eps^(1/3)·max(1, |k_j|),
whose truncation and round-off errors are both O(eps^(2/3)) ≈ 4e-11 relative for smooth maps.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from .structure import Structure


def column_groups(pattern: np.ndarray) -> list[list[int]]:
    """Greedy colouring of the columns of `pattern`: columns in one group share no row."""
    groups: list[list[int]] = []
    used: list[np.ndarray] = []
    # Densest columns first: the usual order that keeps the number of groups small.
    order = sorted(range(pattern.shape[1]), key=lambda j: -int(pattern[:, j].sum()))
    for j in order:
        col = pattern[:, j]
        if not col.any():
            continue
        for g, rows in zip(groups, used, strict=True):
            if not (rows & col).any():
                g.append(j)
                rows |= col
                break
        else:
            groups.append([j])
            used.append(col.copy())
    return [sorted(g) for g in groups]


def _free_pattern(st: Structure) -> np.ndarray:
    """The declared pattern without the identity rows (those need no FMU call)."""
    p = st.pattern.copy()
    for r in st.identity:
        p[r, :] = False
    return p


def _with_identity(st: Structure, jac: np.ndarray) -> np.ndarray:
    for r, j in st.identity.items():
        jac[r, :] = 0.0
        jac[r, j] = 1.0
    return jac


def directional(
    st: Structure,
    dd: Callable[[Sequence[int], Sequence[int], Sequence[float]], Sequence[float]],
    use_dependencies: bool = True,
) -> np.ndarray:
    """[A B; C D] from `dd(unknown_vrs, known_vrs, seeds)` (fmi2GetDirectionalDerivative).

    With `use_dependencies`, only declared nonzeros are asked for, with grouped seeds;
    otherwise one unit seed per known and every unknown.
    """
    unknowns, knowns = st.unknowns, st.knowns
    jac = np.zeros((len(unknowns), len(knowns)))
    pattern = _free_pattern(st)
    if not use_dependencies:
        pattern = np.ones_like(pattern)
        pattern[list(st.identity), :] = False
        groups = [[j] for j in range(len(knowns))]
    else:
        groups = column_groups(pattern)
    for g in groups:
        rows = np.flatnonzero(pattern[:, g].any(axis=1))
        if rows.size == 0:
            continue
        vals = dd([unknowns[r].vr for r in rows], [knowns[j].vr for j in g], [1.0] * len(g))
        for r, v in zip(rows, vals, strict=True):
            cols = [j for j in g if pattern[r, j]]
            jac[r, cols[0]] = v
    return _with_identity(st, jac)


def central_differences(st: Structure, f: Callable[[np.ndarray], np.ndarray], k0: np.ndarray) -> np.ndarray:
    """[A B; C D] by central differences of `f(knowns) -> unknowns` about `k0`.

    Every column is differenced (declared dependencies are not trusted for a fallback);
    identity rows are exact.
    """
    eps = np.finfo(float).eps
    jac = np.zeros((len(st.unknowns), len(st.knowns)))
    for j in range(len(k0)):
        h = eps ** (1 / 3) * max(1.0, abs(k0[j]))
        kp, km = k0.copy(), k0.copy()
        kp[j] += h
        km[j] -= h
        jac[:, j] = (f(kp) - f(km)) / (kp[j] - km[j])
    f(k0)  # leave the FMU at the operating point
    return _with_identity(st, jac)
