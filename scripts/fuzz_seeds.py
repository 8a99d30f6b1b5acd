#!/usr/bin/env python3
"""Seed corpus for canopy_gltf_fuzz (tests/fuzz/gltf_fuzz.h gives the input format).

Every .gltf and .glb under the assets folder (the malformed corpus and the sample models) becomes
one input: the model's bytes, then a "\\n#file:NAME\\n" section for each relative buffer or image
file it names that exists beside it. Inputs over the size limit are left out. The kept regression
inputs are added as they are.
  fuzz_seeds.py ASSETS_DIR OUT_DIR [REGRESSION_DIR] [--max-bytes N]
"""
import hashlib
import json
import os
import sys


def files_named(model_path, data):
    if data[:4] == b"glTF":
        if len(data) < 20:
            return []
        n = int.from_bytes(data[12:16], "little")
        data = data[20:20 + n]
    try:
        doc = json.loads(data.decode("utf-8"))
    except Exception:
        return []
    uris = []
    for key in ("buffers", "images"):
        for item in doc.get(key, []) if isinstance(doc, dict) else []:
            uri = item.get("uri") if isinstance(item, dict) else None
            if isinstance(uri, str) and not uri.startswith("data:") and "://" not in uri:
                uris.append(uri)
    base = os.path.dirname(model_path)
    out = []
    for uri in uris:
        p = os.path.normpath(os.path.join(base, uri))
        if os.path.isfile(p) and p.startswith(base + os.sep):
            out.append((uri, p))
    return out


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    max_bytes = 1 << 20
    if "--max-bytes" in sys.argv:
        max_bytes = int(sys.argv[sys.argv.index("--max-bytes") + 1])
        args = [a for a in args if a != str(max_bytes)]
    assets, out = args[0], args[1]
    os.makedirs(out, exist_ok=True)
    kept = skipped = 0
    for root, _, names in os.walk(assets):
        for name in sorted(names):
            if not name.endswith((".gltf", ".glb")):
                continue
            path = os.path.join(root, name)
            data = open(path, "rb").read()
            for uri, p in files_named(path, data):
                data += b"\n#file:" + uri.encode() + b"\n" + open(p, "rb").read()
            if len(data) > max_bytes:
                skipped += 1
                continue
            open(os.path.join(out, hashlib.sha1(data).hexdigest()), "wb").write(data)
            kept += 1
    if len(args) > 2 and os.path.isdir(args[2]):
        for name in sorted(os.listdir(args[2])):
            data = open(os.path.join(args[2], name), "rb").read()
            open(os.path.join(out, hashlib.sha1(data).hexdigest()), "wb").write(data)
            kept += 1
    print(f"fuzz seeds: {kept} inputs in {out} ({skipped} over {max_bytes} bytes left out)")


main()
