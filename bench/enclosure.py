#!/usr/bin/env python3
"""How much of a Cycles frame's diffuse light is indirect, and how enclosed the frame's
surfaces are, from the render's own passes (README "Against Cycles at equal error").

    /usr/bin/python3 bench/enclosure.py FRAME.exr [FRAME.exr ...]

Per frame, over the geometry pixels (depth below 1e9), means over pixels and R, G, B:
  Ld     direct outgoing radiance, DiffCol x DiffDir + Emit
  Li     indirect outgoing radiance, DiffCol x DiffInd
  total  (Ld + Li) / Ld
  rho    DiffCol, the mean albedo
  Ein    DiffInd, the incoming indirect irradiance over pi
  Ein/L  Ein / (Ld + Li): the incoming indirect light against what the frame's surfaces send
         out; 1 where the surroundings are as bright as the frame and nothing escapes
hbil's automatic fill (unseen_radiance "auto") scales with Ld; a frame whose total is far
above 1 gets much of its indirect light from multiple bounces, and one whose Ein/L is near 1
is enclosed, whatever its frame shows of the sky.

Needs the python3 OpenImageIO bindings (Debian: python3-openimageio) and numpy.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from edge_band import plane, read  # noqa: E402


def rgb(spec, px, name):
    return plane(spec, px, *(name + "." + c for c in "RGB"))


def main():
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    print("| frame | geometry | Ld | Li | total | rho | Ein | Ein/L |")
    print("|---|---|---|---|---|---|---|---|")
    for path in sys.argv[1:]:
        spec, px = read(path)
        geo = plane(spec, px, "Depth.Z")[..., 0] < 1e9
        if not geo.any():
            print("| %s | 0 | | | | | | |" % path)
            continue
        col, ddir, dind = (rgb(spec, px, n) for n in ("DiffCol", "DiffDir", "DiffInd"))
        has_emit = any(c.endswith("Emit.R") for c in spec.channelnames)
        ld = col * ddir + (rgb(spec, px, "Emit") if has_emit else 0.0)
        li = col * dind
        Ld, Li, rho, Ein = (float(a[geo].mean()) for a in (ld, li, col, dind))
        e = Ein / (Ld + Li) if Ld + Li > 0 else float("nan")
        print("| %s | %.2f | %.4f | %.4f | %.2f | %.2f | %.4f | %.2f |" %
              (path, geo.mean(), Ld, Li, (Ld + Li) / Ld if Ld > 0 else float("nan"), rho,
               Ein, e))


if __name__ == "__main__":
    main()
