#!/usr/bin/env python3
"""Writes the seed inputs of the fuzz targets that have no file of their own kind in the repository
(structured .npz inputs, weights and checkpoints, camera texts, small binary files) into
tests/fuzz/seeds/<target>/. Deterministic; run it again after changing a format.
The structured encoding is the one tests/fuzz/fuzz_input.hpp describes."""
import json
import math
import os
import shutil
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
SEEDS = os.path.join(HERE, "seeds")
DTYPES = ["<f4", "<f8", "<i4", "<u4"]


def put(target, name, data):
    os.makedirs(os.path.join(SEEDS, target), exist_ok=True)
    with open(os.path.join(SEEDS, target, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def array(usual, dtype, shape, values=()):
    """One array of a structured input: flags, dims, then up to 255 explicit values."""
    offset = (DTYPES.index(dtype) - DTYPES.index(usual)) % 4
    out = bytes([(offset << 1) | (len(shape) << 3)])
    out += b"".join(struct.pack("<H", d) for d in shape)
    values = list(values)[:255]
    out += bytes([len(values)])
    for v in values:
        out += struct.pack("<i", int(v)) if dtype == "<i4" else struct.pack("<I", int(v) & 0xFFFFFFFF) if dtype == "<u4" else struct.pack("<f", v)
    return out


def structured():
    # bald_sdf.npz: a sphere of radius 1 sampled on 5^3 points over [-2, 2]^3.
    sdf = [math.sqrt((x - 2) ** 2 + (y - 2) ** 2 + (z - 2) ** 2) - 1 for z in range(5) for y in range(5) for x in range(5)]
    put("sdf_grid", "sphere.bin", array("<f4", "<f4", [5, 5, 5], sdf) + array("<f8", "<f8", [3], [-2, -2, -2])
        + array("<f8", "<f8", [1], [1.0]) + array("<f8", "<f8", [1], [0.5]))
    # roots.npz: four roots on faces 0-3.
    n = 4
    vec = lambda v: [c for _ in range(n) for c in v]
    put("roots", "four.bin", array("<u4", "<u4", [n], range(n)) + array("<f4", "<f4", [n, 3], vec([0.2, 0.3, 0.5]))
        + array("<f4", "<f4", [n, 3], [0.1 * i for i in range(3 * n)]) + array("<f4", "<f4", [n, 3], vec([1, 0, 0]))
        + array("<f4", "<f4", [n, 3], vec([0, 0, 1])) + array("<f4", "<f4", [n, 3], vec([0, 1, 0]))
        + array("<f4", "<f4", [n, 3], vec([0, 0, 1])) + array("<i4", "<i4", [n], [0, 1, 2, 3])
        + array("<f4", "<f4", [n], [0.01, 0.02, 0.0, 0.5]))
    # colors.npz: 4 strands of 3 colours, the first not seen.
    put("strand_colors", "four.bin", struct.pack("<B", 4) + array("<f4", "<f4", [n, 3, 3], [0.05 * i for i in range(9 * n)])
        + array("<i4", "<i4", [n], [0, 1, 1, 1]))
    # vertex_fur.npz / frames.npz for 4 vertices (faces).
    put("vertex_fur", "four.bin", struct.pack("<H", n) + array("<i4", "<i4", [n], [0, 1, 2, 3])
        + array("<f4", "<f4", [n], [0.01, 0.02, 0.0, 0.5]) + array("<f4", "<f4", [n, 3], vec([0, 0, 1]))
        + array("<f4", "<f4", [n, 3], vec([1, 0, 0])) + array("<f4", "<f4", [n, 3], vec([0, 1, 0])))
    # A SMAL-shaped model: 33 joints in a chain, 8 vertices, 2 shape directions.
    V, F, S, J = 8, 4, 2, 33
    verts = [c for i in range(V) for c in ((i & 1) * 1.0, (i >> 1 & 1) * 1.0, (i >> 2 & 1) * 1.0)]
    kintree = [-1] + list(range(J - 1)) + list(range(J))
    put("smal_model", "chain.bin", array("<f8", "<f8", [V, 3], verts) + array("<u4", "<u4", [F, 3], [0, 1, 2, 1, 3, 2, 4, 5, 6, 5, 7, 6])
        + array("<f8", "<f8", [V, 3, S]) + array("<f8", "<f8", [J, V]) + array("<i4", "<i4", [2, J], kintree)
        + array("<f8", "<f8", [V, J]))
    # cameras_sphere.npz: two 3x4 projections P = K [I | t].
    P = lambda tx: [100, 0, 4, 100 * tx + 4 * 3, 0, 100, 3, 3 * 3, 0, 0, 1, 3]
    put("scene_neus", "two.bin", array("<f8", "<f8", [3, 4], P(0.0)) + array("<f8", "<f8", [3, 4], P(0.5)))


def weights_file(config, tensors):
    data, entries = b"", []
    for name, shape, values in tensors:
        entries.append({"name": name, "shape": shape, "offset": len(data), "count": len(values)})
        data += struct.pack("<%df" % len(values), *values)
    header = json.dumps({"config": config, "tensors": entries}).encode()
    return b"NFWT" + struct.pack("<II", 1, len(header)) + header + data


def adam(prefix, count):
    return [(prefix + ".m", [count], [0.0] * count), (prefix + ".v", [count], [0.0] * count),
            (prefix + ".state", [7], [0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0])]


def checkpoints():
    fur_report = {"step": 3, "warm": False, "view": 1, "loss": 1.5, "silhouette": 0.1, "orientation": 0.2, "direction": 0.3,
                  "chamfer": 0.4, "penetration": 0.0, "curvature": 0.01, "seconds": 0.5, "chamfer_unmatched": 0, "lr": 0.001,
                  "grad_norm": 2.0, "skipped_steps": 0}
    fur = {"kind": "fur checkpoint", "version": 1, "field": {}, "options": {}, "step": 3, "seconds": 1.5, "last": fur_report,
           "history": [fur_report]}
    put("checkpoint", "fur.bin", b"\x01" + weights_file(fur, [("field", [4], [0.1, 0.2, 0.3, 0.4])] + adam("adam.field", 4)))
    put("checkpoint", "fur_decoder.bin", b"\x03" + weights_file(fur, [("field", [2], [0.1, 0.2]), ("decoder", [2], [1.0, 2.0])]
                                                                  + adam("adam.field", 2) + adam("adam.decoder", 2)))
    neus_report = {"step": 3, "seconds": 0.5, "loss": 0.2, "colour_l1": 0.1, "mask_bce": 0.05, "eikonal": 0.01, "psnr": 20.0,
                   "inv_s": 30.0, "lr": 0.01, "rays_per_second": 1000.0, "skipped_steps": 0}
    neus = {"kind": "neus checkpoint", "version": 1, "field": {}, "options": {}, "step": 3, "seconds": 1.5, "variance": 0.3,
            "variance_adam": [0.0, 0.0, 3], "last": neus_report, "history": [neus_report]}
    tensors = [("hash_table", [4], [0.0] * 4), ("sdf", [3], [0.1, 0.2, 0.3]), ("colour", [2], [0.5, 0.5]), ("occupancy", [8], [1.0] * 8)]
    tensors += adam("adam.hash_table", 4) + adam("adam.sdf", 3) + adam("adam.colour", 2)
    put("checkpoint", "neus.bin", b"\x02" + weights_file(neus, tensors))
    put("weights", "mlp.nfwt", weights_file({"kind": "mlp", "layers": [2, 1]}, [("layer0.weight", [1, 2], [0.5, -0.5]),
                                                                               ("layer0.bias", [1], [0.1])]))


def npy(values, shape):
    header = "{'descr': '<f4', 'fortran_order': False, 'shape': (%s), }" % "".join("%d," % d for d in shape)
    header = header.ljust(117) + "\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode() + struct.pack("<%df" % len(values), *values)


def zip_stored(members):
    """A zip archive with stored members (what numpy.savez writes)."""
    out, central = b"", b""
    for name, data in members:
        crc, offset, n = zlib.crc32(data), len(out), name.encode()
        out += struct.pack("<IHHHHHIIIHH", 0x04034B50, 20, 0, 0, 0, 0, crc, len(data), len(data), len(n), 0) + n + data
        central += struct.pack("<IHHHHHHIIIHHHHHII", 0x02014B50, 20, 20, 0, 0, 0, 0, crc, len(data), len(data), len(n), 0, 0, 0, 0, 0,
                               offset) + n
    return out + central + struct.pack("<IHHHHIIH", 0x06054B50, 0, 0, len(members), len(members), len(central), len(out), 0)


def copy(target, name, to_target, to_name):
    os.makedirs(os.path.join(SEEDS, to_target), exist_ok=True)
    shutil.copy(os.path.join(SEEDS, target, name), os.path.join(SEEDS, to_target, to_name))


def exr_gray(width, height, values):
    """An uncompressed scanline OpenEXR file with one FLOAT channel Y."""
    attr = lambda name, kind, data: name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data
    header = attr("channels", "chlist", b"Y\0" + struct.pack("<iBBBBii", 2, 0, 0, 0, 0, 1, 1) + b"\0")
    header += attr("compression", "compression", b"\0")
    window = struct.pack("<4i", 0, 0, width - 1, height - 1)
    header += attr("dataWindow", "box2i", window) + attr("displayWindow", "box2i", window)
    header += attr("lineOrder", "lineOrder", b"\0") + attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
    header += attr("screenWindowCenter", "v2f", struct.pack("<2f", 0, 0)) + attr("screenWindowWidth", "float", struct.pack("<f", 1.0))
    start = 8 + len(header) + 1 + 8 * height
    lines, offsets = b"", []
    for y in range(height):
        offsets.append(start + len(lines))
        row = struct.pack("<%df" % width, *values[y * width:(y + 1) * width])
        lines += struct.pack("<ii", y, len(row)) + row
    return b"\x76\x2f\x31\x01" + struct.pack("<I", 2) + header + b"\0" + b"".join(struct.pack("<Q", o) for o in offsets) + lines


def small_files():
    put("npz", "two.npz", zip_stored([("a.npy", npy([1.0, 2.0, 3.0, 4.0, 5.0, 6.0], [2, 3])), ("b.npy", npy([0.5], [1]))]))
    shutil.copy(os.path.join(SEEDS, "hair_stream", "hair_stream.hair"), os.path.join(SEEDS, "hair", "hair.hair")) if os.path.isdir(
        os.path.join(SEEDS, "hair")) else (os.makedirs(os.path.join(SEEDS, "hair")), shutil.copy(
            os.path.join(SEEDS, "hair_stream", "hair_stream.hair"), os.path.join(SEEDS, "hair", "hair.hair")))
    pts = [(0, 0, 0), (0, 0.1, 0), (0, 0.2, 0.05), (1, 0, 0), (1, 0.1, 0)]
    body = b"".join(struct.pack("<4f", *p, 0.01) for p in pts) + struct.pack("<2i", 0, 1) + struct.pack("<2i", 1, 2) + struct.pack("<2i", 3, 4)
    body += struct.pack("<iiH", 0, 3, 2) + struct.pack("<iiH", 3, 2, 5)
    put("strands_ply", "two.ply", b"ply\nformat binary_little_endian 1.0\ncomment nf_gpu strands: polylines as vertex chains\n"
        b"element vertex 5\nproperty float x\nproperty float y\nproperty float z\nproperty float thickness\n"
        b"element edge 3\nproperty int vertex1\nproperty int vertex2\n"
        b"element strand 2\nproperty int first\nproperty int count\nproperty ushort region\nend_header\n" + body)
    copy("image_png", "image_png.png", "image_size", "image_png.png")
    put("image_exr", "gray.exr", exr_gray(2, 2, [0.0, 0.25, 0.5, 1.0]))
    gray16 = os.path.join(HERE, "..", "io", "data", "gray16.png")
    shutil.copy(gray16, os.path.join(SEEDS, "image_png", "gray16.png"))
    put("scene_text", "colmap.txt", b"\x00" + struct.pack("<H", 62) +
        b"1 PINHOLE 8 6 100 100 4 3\n2 SIMPLE_RADIAL 8 6 100 4 3 0\n#end\n12" +
        b"1 1 0 0 0 0 0 3 1 img_0000.png\n\n2 0.7071 0 0.7071 0 0 0 3 2 img_0001.png\n1 2 3\n")
    put("scene_text", "artemis.txt", b"\x01" + struct.pack("<H", 48) + b"0 0 1 1 0 0 0 1 0 0 0 -3\n0 0 1 1 0 0 0 1 0 0.5 0 -3\n"
        b"0 100 0 4 0 100 3 0 0 1\n1 100 0 4 0 100 3 0 0 1\n")
    record = {"stage": "fur", "key": {"version": 1, "parameters": {"steps": 300}, "inputs": {"WORK/frames/roots.npz": "ab12"}},
              "summary": {"strands": 1000, "f_score": {"2cm_20": 91.0}}, "seconds": 12.5, "finished": "2026-12-01T10:00:00Z"}
    put("stage_record", "stage.json", json.dumps(record, indent=2) + "\n")
    put("fur_view", "native.nfview", fur_view(True))
    put("fur_view", "whole.nfview", fur_view(False))


def fur_view(native):
    # A 3 x 2 crop of camera "000" (64 x 48) at half scale, with or without a native crop.
    n = 6
    crop = struct.pack("<II4d", 3, 2, 30.0, 30.0, 1.5, 1.0)
    body = b"NFFURVW\0" + struct.pack("<II", 1, 0) + struct.pack("<I", 3) + b"000" + crop + struct.pack("<2d", 0.4, 0.5)
    for k in range(6):
        body += struct.pack("<Q", n) + struct.pack("<6f", *[0.1 * (i + k) for i in range(n)])
    body += struct.pack("<Q", 3 * n) + struct.pack("<18f", *[0.05 * i for i in range(3 * n)])
    body += struct.pack("<B", 1) + struct.pack("<II4d", 6, 4, 60.0, 60.0, 3.0, 2.0) if native else struct.pack("<B", 0)
    return body


def vlm_answers():
    put("vlm_answer", "lengths.txt", '{"leg_front": 0.8, "leg_rear": 0.9, "paws": 0.45, "belly": 1.25, "neck": 1.2, "head": 0.6, '
        '"ears": 0.5, "tail": 2.5, "back": 1.5}')
    put("vlm_answer", "prose.txt", "Sure! Here is my estimate:\n```python\n{'tail': '3 cm', 'head': 1, 'direction': [0, -1, 1]}\n```\n"
        "The eyes are about 3.2 cm apart.")


def main():
    structured()
    checkpoints()
    small_files()
    vlm_answers()


if __name__ == "__main__":
    main()
