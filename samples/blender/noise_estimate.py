#!/usr/bin/env python3
"""Per-pixel noise of a Cycles render from two renders that differ only in seed.

    python3 samples/blender/noise_estimate.py seed1.exr seed2.exr [--json out.json]

For independent renders a and b of the same frame, std_pixel ~= RMS(a - b) / sqrt(2).
Reported per pass (first channel of each RGB pass, all channels of Combined
averaged), over geometry pixels only (Depth.Z < 1e9): RMS std, mean value,
and the 95th / 99th percentile of |a - b| / sqrt(2).
"""
import json
import sys

import numpy as np
import OpenImageIO as oiio


def load(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise SystemExit("cannot open %s" % path)
    spec = inp.spec()
    px = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    inp.close()
    return {n: px[..., i] for i, n in enumerate(spec.channelnames)}


def main(argv):
    out_json = None
    if "--json" in argv:
        i = argv.index("--json")
        out_json = argv[i + 1]
        argv = argv[:i] + argv[i + 2:]
    a, b = load(argv[0]), load(argv[1])
    depth = [n for n in a if n.endswith(".Depth.Z")]
    mask = a[depth[0]] < 1e9 if depth else np.ones(next(iter(a.values())).shape, bool)
    passes = {}
    for n in sorted(a):
        if n not in b:
            continue
        layer, _, chan = n.rpartition(".")
        passes.setdefault(layer, []).append(n)
    res = {"pixels": int(mask.sum())}
    for layer, chans in passes.items():
        if layer.endswith((".Depth", ".Position", ".Normal", ".Vector")):
            continue
        chans = [c for c in chans if not c.endswith(".A")]
        d = np.stack([(a[c] - b[c])[mask] for c in chans]) / np.sqrt(2.0)
        v = np.stack([0.5 * (a[c] + b[c])[mask] for c in chans])
        ad = np.abs(d)
        res[layer] = {"rms_std": float(np.sqrt(np.mean(d * d))),
                      "mean": float(v.mean()),
                      "p95": float(np.percentile(ad, 95)),
                      "p99": float(np.percentile(ad, 99))}
    for k, v in res.items():
        if isinstance(v, dict):
            print("%-24s rms_std %.4f  mean %.4f  p95 %.4f  p99 %.4f"
                  % (k, v["rms_std"], v["mean"], v["p95"], v["p99"]))
        else:
            print("%s %s" % (k, v))
    if out_json:
        with open(out_json, "w") as f:
            json.dump(res, f, indent=2)
            f.write("\n")


if __name__ == "__main__":
    main(sys.argv[1:])
