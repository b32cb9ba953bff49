"""Linearizations to and from files, in the layouts of `mbfmu linearize`:

- `.json`: a list of objects `{"time", "states", "inputs", "outputs", "A", "B", "C", "D"}`
  (plus units, operating point, method and model, which the CLI's reader ignores).
  Floats are written with `repr`, so they read back exactly.
- `.npz`: arrays `A B C D time` and the names as string arrays; with several
  linearizations every array gets the suffix `_k`, as the CLI writes them.
- `.mat`: MATLAB v4 (readable by MATLAB, Octave and `scipy.io.loadmat`), the same names;
  string lists are text matrices, one name per row, padded with blanks.
"""

from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np

from .errors import ArgumentError, FMUNotFoundError, MbfmuError
from .linearization import Linearization

_LISTS = ("states", "inputs", "outputs", "state_units", "input_units", "output_units")
_VECTORS = ("x0", "u0", "y0")


def _fields(lin: Linearization) -> dict:
    d = {"time": lin.time}
    for k in _LISTS:
        d[k] = list(getattr(lin, k))
    for k in ("A", "B", "C", "D"):
        d[k] = getattr(lin, k)
    for k in _VECTORS:
        v = getattr(lin, k)
        if v is not None:
            d[k] = np.asarray(v, dtype=float)
    d["method"] = lin.method
    d["model"] = lin.model
    return d


def _text(v) -> str:
    """A string saved as a str, a 0-d array or a one-row text matrix."""
    if isinstance(v, (list, tuple)):
        return str(v[0]) if v else ""
    return str(v)


def _build(d: dict) -> Linearization:
    try:
        kw = {k: [str(s) for s in d.get(k, [])] for k in _LISTS}
        # Files without names (the CLI's npz and mat) get positional ones: x1.., u1.., y1..
        shapes = {"states": np.shape(d["A"])[0], "inputs": np.shape(d["B"])[1], "outputs": np.shape(d["C"])[0]}
        for k, letter in (("states", "x"), ("inputs", "u"), ("outputs", "y")):
            if k not in d:
                kw[k] = [f"{letter}{i + 1}" for i in range(shapes[k])]
        n, m, p = len(kw["states"]), len(kw["inputs"]), len(kw["outputs"])
        mats = {
            k: np.asarray(d[k], dtype=float).reshape(shape)
            for k, shape in (("A", (n, n)), ("B", (n, m)), ("C", (p, n)), ("D", (p, m)))
        }
        vecs = {k: (np.asarray(d[k], dtype=float).reshape(-1) if d.get(k) is not None else None) for k in _VECTORS}
        return Linearization(
            time=float(np.asarray(d["time"]).reshape(-1)[0]),
            **mats,
            **kw,
            **vecs,
            method=_text(d.get("method", "directional derivatives")),
            model=_text(d.get("model", "")),
        )
    except (KeyError, ValueError, IndexError) as e:
        raise MbfmuError(f"not a linearization: {e}") from e


def _kind(path: Path) -> str:
    ext = path.suffix.lower()
    if ext not in (".json", ".npz", ".mat"):
        raise ArgumentError(f"'{path}': unknown file type '{ext}' (expected .json, .npz or .mat)")
    return ext


def save(lins, path) -> None:
    """Write one Linearization or a list of them to `path` (.json, .npz or .mat)."""
    if isinstance(lins, Linearization):
        lins = [lins]
    path = Path(path)
    ext = _kind(path)
    items = [_fields(lin) for lin in lins]
    if ext == ".json":

        def plain(v):
            return v.tolist() if isinstance(v, np.ndarray) else v

        path.write_text(json.dumps([{k: plain(v) for k, v in d.items()} for d in items]))
        return
    arrays = {}
    for i, d in enumerate(items):
        sfx = f"_{i}" if len(items) > 1 else ""
        for k, v in d.items():
            arrays[k + sfx] = v
    if ext == ".npz":
        np.savez(
            path,
            **{k: (np.array(v, dtype=str) if isinstance(v, (list, str)) else np.asarray(v)) for k, v in arrays.items()},
        )
    else:
        _write_mat_v4(path, arrays)


def load(path) -> list[Linearization]:
    """Read the linearizations of a file written by `save` or by `mbfmu linearize`."""
    path = Path(path)
    ext = _kind(path)
    if not path.exists():
        raise FMUNotFoundError(f"'{path}' does not exist")
    if ext == ".json":
        data = json.loads(path.read_text())
        return [_build(d) for d in (data if isinstance(data, list) else [data])]
    if ext == ".npz":
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    else:
        arrays = _read_mat_v4(path)
    arrays = {k: (v.tolist() if v.dtype.kind == "U" else v) for k, v in arrays.items()}
    if "A" in arrays:
        return [_build(arrays)]
    out = []
    k = 0
    while f"A_{k}" in arrays:
        out.append(_build({name[: -len(f"_{k}")]: v for name, v in arrays.items() if name.endswith(f"_{k}")}))
        k += 1
    if not out:
        raise MbfmuError(f"'{path}' holds no linearization (no array A or A_0)")
    return out


# --- MATLAB v4 ------------------------------------------------------------------------
# Each matrix: five int32 (type, rows, cols, imagf, namelen), the name with a NUL, the data
# column-major. type = 0 (little-endian IEEE double, full numeric) or 1 (text: character
# codes as doubles).


def _write_mat_v4(path: Path, arrays: dict) -> None:
    out = bytearray()
    for name, v in arrays.items():
        if isinstance(v, str):
            v = [v]
        if isinstance(v, list):
            width = max((len(s) for s in v), default=0)
            mat = np.array([[ord(c) for c in s.ljust(width)] for s in v], dtype=float).reshape(len(v), width)
            kind = 1
        else:
            mat = np.atleast_2d(np.asarray(v, dtype=float))
            if np.asarray(v).ndim == 1:
                mat = mat.reshape(-1, 1)
            kind = 0
        rows, cols = mat.shape
        out += struct.pack("<5i", kind, rows, cols, 0, len(name) + 1)
        out += name.encode("ascii") + b"\0"
        out += mat.astype("<f8").tobytes(order="F")
    path.write_bytes(bytes(out))


def _read_mat_v4(path: Path) -> dict:
    b = path.read_bytes()
    pos = 0
    arrays = {}
    while pos < len(b):
        kind, rows, cols, imagf, namelen = struct.unpack_from("<5i", b, pos)
        if kind not in (0, 1) or imagf != 0 or rows < 0 or cols < 0:
            raise MbfmuError(f"'{path}': not a little-endian real MATLAB v4 file written by mbfmu")
        pos += 20
        name = b[pos : pos + namelen - 1].decode("ascii")
        pos += namelen
        data = np.frombuffer(b, dtype="<f8", count=rows * cols, offset=pos).reshape((rows, cols), order="F")
        pos += 8 * rows * cols
        if kind == 1:
            arrays[name] = np.array(["".join(chr(int(c)) for c in row).rstrip(" ") for row in data], dtype=str)
        else:
            arrays[name] = data.copy()
    return arrays
