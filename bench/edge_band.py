#!/usr/bin/env python3
"""Error of hbil's composite and indirect light in the band along the frame's edge and in
the interior, against a path-traced reference (README "Light from beyond the frame").

    /usr/bin/python3 bench/edge_band.py OUT_PATTERN REF_PATTERN FRAMES [BAND]

OUT_PATTERN: hbil's output frames (out/frame_####.exr), with or without a guard band: their
pixels are taken where the reference's are (the display window), by the EXR windows.
REF_PATTERN: Blender main renders of the frame alone (Combined, DiffCol, DiffInd, AO, Depth).
FRAMES: A-B. BAND: the band's width as a fraction of the frame's width and height (0.1).
Prints, per frame and over all frames, the RMSE of composite (R, G, B against Combined), of
indirect (against DiffCol x DiffInd) and of ao (against the AO pass) in the band and inside
it, over the reference's geometry pixels (depth below 1e9).

Needs the python3 OpenImageIO bindings (Debian: python3-openimageio) and numpy.
"""
import sys

import numpy as np
import OpenImageIO as oiio


def read(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise SystemExit("cannot open %s: %s" % (path, oiio.geterror()))
    spec = inp.spec()
    px = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    inp.close()
    return spec, px


def plane(spec, px, *names):
    idx = []
    for n in names:
        hits = [i for i, c in enumerate(spec.channelnames) if c == n or c.endswith("." + n)]
        if not hits:
            raise SystemExit("no channel %s in the image" % n)
        idx.append(hits[0])
    return px[..., idx]


def main(argv):
    if len(argv) < 3:
        print(__doc__)
        return 2
    out_pat, ref_pat, frames = argv[0], argv[1], argv[2]
    band = float(argv[3]) if len(argv) > 3 else 0.1
    a, b = (int(v) for v in frames.split("-"))
    sums = {k: [0.0, 0] for k in ("composite band", "composite inside", "indirect band",
                                  "indirect inside", "ao band", "ao inside")}
    print("| frame | composite band | composite inside | indirect band | indirect inside "
          "| ao band | ao inside |")
    print("|---|---|---|---|---|---|---|")
    for f in range(a, b + 1):
        rs, rp = read(ref_pat.replace("####", "%04d" % f))
        os_, op = read(out_pat.replace("####", "%04d" % f))
        dx, dy = rs.x - os_.x, rs.y - os_.y
        if dx < 0 or dy < 0 or dx + rs.width > os_.width or dy + rs.height > os_.height:
            raise SystemExit("frame %d: the reference's pixels do not lie within the output's" % f)
        op = op[dy:dy + rs.height, dx:dx + rs.width]
        geo = plane(rs, rp, "Depth.Z")[..., 0] < 1e9
        h, w = geo.shape
        bx, by = int(round(band * w)), int(round(band * h))
        inside = np.zeros_like(geo)
        inside[by:h - by, bx:w - bx] = True
        pairs = {
            "composite": (plane(os_, op, "composite.R", "composite.G", "composite.B"),
                          plane(rs, rp, "Combined.R", "Combined.G", "Combined.B")),
            "indirect": (plane(os_, op, "indirect.R", "indirect.G", "indirect.B"),
                         plane(rs, rp, "DiffCol.R", "DiffCol.G", "DiffCol.B") *
                         plane(rs, rp, "DiffInd.R", "DiffInd.G", "DiffInd.B")),
            "ao": (plane(os_, op, "ao.Y"), plane(rs, rp, "AO.R")),
        }
        row = []
        for layer, (t, r) in pairs.items():
            err2 = ((t - r) ** 2).mean(axis=-1)
            for where, m in (("band", geo & ~inside), ("inside", geo & inside)):
                s = sums["%s %s" % (layer, where)]
                s[0] += float(err2[m].sum())
                s[1] += int(m.sum())
                row.append("%.5f" % np.sqrt(err2[m].mean()))
        print("| %d | %s |" % (f, " | ".join(row)))
    print("| all | %s |" % " | ".join("%.5f" % np.sqrt(s[0] / s[1]) for s in sums.values()))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
