#!/usr/bin/env python3
"""Convert the official SMAL model (.pkl, e.g. smal_CVPR2017.pkl) to the .npz that nf_gpu loads
with `--set body.model=FILE.npz`.

The .pkl is a Python 2 pickle of numpy arrays, chumpy objects and a scipy sparse J_regressor.
This converter needs neither chumpy nor scipy: a small unpickling shim takes the arrays out of
chumpy objects (their 'x') and densifies the sparse matrix from its CSC fields. It needs numpy
(Debian: python3-numpy). Nothing of SMAL is shipped with nf_gpu; the model's licence stays with
the user's copy.

usage: tools/smal_to_npz.py smal_CVPR2017.pkl smal.npz
"""
import io
import pickle
import sys

import numpy as np

ARRAYS = ("v_template", "f", "shapedirs", "J_regressor", "kintree_table", "weights", "posedirs")
REQUIRED = ARRAYS[:-1]


class _Chumpy:
    """Stands in for any chumpy class: keeps the pickled state; its value is state['x']."""

    def __init__(self, *args, **kwargs):
        self.state = {}

    def __setstate__(self, state):
        self.state = state if isinstance(state, dict) else {"x": state}

    def array(self):
        if "x" not in self.state:
            raise ValueError("a chumpy object without 'x' (a derived expression) cannot be converted")
        return to_array(self.state["x"])


class _SparseCSC:
    """Stands in for scipy.sparse.csc_matrix: keeps data/indices/indptr/shape."""

    def __init__(self, *args, **kwargs):
        self.state = {}

    def __setstate__(self, state):
        self.state = state

    def array(self):
        s = self.state
        shape = s.get("_shape", s.get("shape"))
        dense = np.zeros(shape, dtype=np.float64)
        data, indices, indptr = (np.asarray(s[k]) for k in ("data", "indices", "indptr"))
        for col in range(shape[1]):
            rows = indices[indptr[col]:indptr[col + 1]]
            dense[rows, col] = data[indptr[col]:indptr[col + 1]]
        return dense


class _Unpickler(pickle.Unpickler):
    def find_class(self, module, name):
        if module.startswith("chumpy"):
            return _Chumpy
        if module.startswith("scipy.sparse"):
            if "csc" not in module and name != "csc_matrix":
                raise pickle.UnpicklingError(f"unsupported sparse format {module}.{name}")
            return _SparseCSC
        return super().find_class(module, name)


def to_array(value):
    if isinstance(value, (_Chumpy, _SparseCSC)):
        return value.array()
    return np.asarray(value)


def load_pkl(data):
    return _Unpickler(io.BytesIO(data), encoding="latin1").load()


def convert(pkl_path, npz_path):
    with open(pkl_path, "rb") as f:
        model = load_pkl(f.read())
    if not isinstance(model, dict):
        raise SystemExit(f"{pkl_path}: not a SMAL model (expected a dict of arrays)")
    missing = [k for k in REQUIRED if k not in model]
    if missing:
        raise SystemExit(f"{pkl_path}: not a SMAL model, missing {', '.join(missing)}")
    out = {}
    for key in ARRAYS:
        if key in model:
            out[key] = to_array(model[key])
    out["f"] = out["f"].astype(np.uint32)
    out["kintree_table"] = out["kintree_table"].astype(np.int64)
    for key in ("v_template", "shapedirs", "J_regressor", "weights", "posedirs"):
        if key in out:
            out[key] = out[key].astype(np.float64)
    v = out["v_template"].shape[0]
    j = out["J_regressor"].shape[0]
    checks = [("v_template", (v, 3)), ("J_regressor", (j, v)), ("kintree_table", (2, j)), ("weights", (v, j))]
    for key, shape in checks:
        if out[key].shape != shape:
            raise SystemExit(f"{pkl_path}: {key} has shape {out[key].shape}, expected {shape}")
    if out["shapedirs"].shape[:2] != (v, 3):
        raise SystemExit(f"{pkl_path}: shapedirs has shape {out['shapedirs'].shape}, expected ({v}, 3, shapes)")
    np.savez(npz_path, **out)
    return {k: (a.shape, str(a.dtype)) for k, a in out.items()}


def main(argv):
    if len(argv) != 3:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    for key, (shape, dtype) in convert(argv[1], argv[2]).items():
        print(f"{key:14s} {str(shape):18s} {dtype}")
    print(f"wrote {argv[2]}; use it with: nf_gpu reconstruct ... --set body.model={argv[2]}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
