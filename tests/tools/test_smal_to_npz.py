#!/usr/bin/env python3
"""tools/smal_to_npz.py on a pickle shaped like the official SMAL file: chumpy objects and a scipy
CSC J_regressor, written by stand-in classes registered under chumpy's and scipy's module names,
so the converter's shim is exercised without either package (as on a user's machine)."""
import os
import pickle
import sys
import tempfile
import types

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "tools"))
import smal_to_npz  # noqa: E402


def fake_module(name, cls_name):
    parts = name.split(".")
    for k in range(1, len(parts)):  # the parent packages, as an import would make them
        sys.modules.setdefault(".".join(parts[:k]), types.ModuleType(".".join(parts[:k])))
    module = types.ModuleType(name)
    cls = type(cls_name, (), {"__module__": name, "__getstate__": lambda self: self.__dict__})
    module.__dict__[cls_name] = cls
    sys.modules[name] = module
    return cls


def main():
    Ch = fake_module("chumpy.ch", "Ch")
    Csc = fake_module("scipy.sparse.csc", "csc_matrix")
    rng = np.random.default_rng(1)
    v, j, s = 3889, 33, 41
    v_template = rng.normal(size=(v, 3))
    regressor = np.zeros((j, v))
    for k in range(j):
        regressor[k, rng.choice(v, 4, replace=False)] = 0.25
    sparse = Csc()
    cols = [np.nonzero(regressor[:, c])[0] for c in range(v)]
    sparse.__dict__.update(
        data=np.concatenate([regressor[r, c] for c, r in enumerate(cols)]),
        indices=np.concatenate(cols).astype(np.int32),
        indptr=np.concatenate([[0], np.cumsum([len(r) for r in cols])]).astype(np.int32),
        _shape=(j, v))
    shapedirs = Ch()
    shapedirs.__dict__["x"] = rng.normal(size=(v, 3, s))
    weights = rng.random(size=(v, j))
    weights /= weights.sum(axis=1, keepdims=True)
    model = {
        "v_template": v_template, "f": rng.integers(0, v, size=(7774, 3)).astype(np.uint32), "shapedirs": shapedirs,
        "J_regressor": sparse, "kintree_table": np.stack([np.arange(j) - 1, np.arange(j)]), "weights": weights,
        "posedirs": np.zeros((v, 3, (j - 1) * 9)), "bs_type": "lrotmin",
    }
    failures = 0
    with tempfile.TemporaryDirectory() as d:
        pkl, npz = os.path.join(d, "smal.pkl"), os.path.join(d, "smal.npz")
        with open(pkl, "wb") as f:
            pickle.dump(model, f, protocol=2)
        for name in ("chumpy.ch", "chumpy", "scipy.sparse.csc", "scipy.sparse", "scipy"):  # a user's machine has neither
            del sys.modules[name]
        smal_to_npz.convert(pkl, npz)
        out = np.load(npz)
        expected = {"v_template": ((v, 3), "float64"), "f": ((7774, 3), "uint32"), "shapedirs": ((v, 3, s), "float64"),
                    "J_regressor": ((j, v), "float64"), "kintree_table": ((2, j), "int64"),
                    "weights": ((v, j), "float64"), "posedirs": ((v, 3, 288), "float64")}
        checks = [(f"{k} {shape} {dtype}", out[k].shape == shape and str(out[k].dtype) == dtype)
                  for k, (shape, dtype) in expected.items()]
        checks.append(("J_regressor densified exactly", np.array_equal(out["J_regressor"], regressor)))
        checks.append(("shapedirs taken from the chumpy object", np.array_equal(out["shapedirs"], shapedirs.x)))
        bad = os.path.join(d, "bad.pkl")
        with open(bad, "wb") as f:
            pickle.dump({"v_template": v_template}, f, protocol=2)
        try:
            smal_to_npz.convert(bad, os.path.join(d, "bad.npz"))
            checks.append(("a pickle without SMAL's arrays is refused", False))
        except SystemExit as e:
            checks.append(("a pickle without SMAL's arrays is refused", "missing f" in str(e)))
    for name, ok in checks:
        print(("ok   " if ok else "FAIL ") + name)
        failures += not ok
    print(f"{len(checks) - failures} passed, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
