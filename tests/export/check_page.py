#!/usr/bin/env python3
"""Checks an export folder's index.html in a headless Chromium: every image it names exists and
loads (the page marks how many did on its <body>), the browser logs no error for the page, and a
screenshot shows the previews (many colours where the first image sits, not a blank page).
Usage: check_page.py EXPORT_DIR OUT_DIR. Exit 1 on a failed check."""
import os
import re
import struct
import subprocess
import sys
import zlib

folder, out = sys.argv[1], sys.argv[2]
page = os.path.join(os.path.abspath(folder), "index.html")
url = "file://" + page
chromium = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--virtual-time-budget=5000"]
failed = []


def check(name, ok, detail):
    print(f"export page test: {'PASS' if ok else 'FAIL'} {name}: {detail}")
    if not ok:
        failed.append(name)


html = open(page, encoding="utf-8").read()
images = re.findall(r'<img src="([^"]+)"', html)
missing = [i for i in images if not os.path.exists(os.path.join(folder, i))]
check("images exist", images and not missing, f"{len(images)} images named, missing: {missing}")

dom = subprocess.run(chromium + ["--enable-logging=stderr", "--v=0", "--dump-dom", url], capture_output=True, text=True, timeout=120)
loaded = re.search(r'data-images-loaded="(\d+)"', dom.stdout)
check("images load", loaded and int(loaded.group(1)) == len(images), f"{loaded.group(1) if loaded else 'no'} of {len(images)} loaded")
console = [line for line in dom.stderr.splitlines() if "CONSOLE" in line or "Uncaught" in line or "Failed to load resource" in line]
check("no console errors", not console, "; ".join(console[:3]) or "none")

shot = os.path.join(out, "page.png")
subprocess.run(chromium + ["--window-size=1000,1400", f"--screenshot={shot}", url], capture_output=True, timeout=120)


def read_png(path):
    """8-bit RGB or RGBA PNG -> (width, height, channels, rows of bytes)."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    at, idat, width = 8, b"", 0
    while at < len(data):
        length, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + length]
        if kind == b"IHDR":
            width, height, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and ctype in (2, 6), f"PNG depth {depth} colour type {ctype}"
            channels = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        at += 12 + length
    raw, stride, rows, prev = zlib.decompress(idat), width * channels, [], bytearray(width * channels)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b, c = prev[i], prev[i - channels] if i >= channels else 0
            if f == 1: line[i] = (line[i] + a) & 255
            elif f == 2: line[i] = (line[i] + b) & 255
            elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, channels, rows


ok = os.path.exists(shot)
detail = "no screenshot"
if ok:
    w, h, ch, rows = read_png(shot)
    # The first preview sits under the title: its band of the page holds the render's colours, which
    # are not greys (a page without its images shows only grey text, grey frames and white).
    colours = set()
    for y in range(h // 12, h // 3):
        row = rows[y]
        for x in range(0, w // 2, 2):
            r, g, b = row[x * ch:x * ch + 3]
            if max(r, g, b) - min(r, g, b) > 12:
                colours.add((r, g, b))
    ok = len(colours) > 500  # measured: 2,573 on the test scene, 87 with its images missing
    detail = f"{w}x{h} screenshot, {len(colours)} distinct non-grey colours where the turntable is"
check("screenshot shows the previews", ok, detail)
print("export page test:", "passed" if not failed else "FAILED " + ", ".join(failed))
sys.exit(1 if failed else 0)
