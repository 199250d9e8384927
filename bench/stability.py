#!/usr/bin/env python3
"""Temporal measures for bench/measure.sh, from hbil outputs and the Cycles frames.

    stability.py flicker OUT_PATTERN FRAMES
        mean |composite_k - composite_(k-1)| / mean composite over geometry pixels (alpha > 0),
        averaged over consecutive frame pairs
    stability.py changes OUT_PATTERN REF_PATTERN FRAMES
        the same flicker measure for hbil's composite and for the reference's Combined (a moving
        camera changes the true image too; hbil should change as much as the reference, no more)
    stability.py disocclusion OUT_PATTERN REF_PATTERN FRAMES
        RMSE of indirect against the reference's DiffCol*DiffInd over pixels whose history.Y
        is 1 (newly revealed: no accepted history) and over pixels with history > 1, frames
        after the first

FRAMES is A-B. Patterns use #### for the frame number. Needs python3-openimageio, numpy.
"""
import sys

import numpy as np
import OpenImageIO as oiio


def channels(path, names):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise SystemExit("cannot open %s: %s" % (path, oiio.geterror()))
    spec = inp.spec()
    out = []
    for n in names:
        k = list(spec.channelnames).index(n)
        out.append(inp.read_image(0, 0, k, k + 1, oiio.FLOAT)[:, :, 0])
    inp.close()
    return out


def frame_path(pattern, f):
    return pattern.replace("####", "%04d" % f)


def frames(text):
    a, b = text.split("-")
    return list(range(int(a), int(b) + 1))


def flicker(out, fr, prefix="composite.", quiet=False):
    rgb = [prefix + "R", prefix + "G", prefix + "B"]
    prev = None
    values = []
    for f in fr:
        c = channels(frame_path(out, f), rgb + [prefix + "A"])
        img, alpha = np.stack(c[:3], -1), c[3]
        if prev is not None:
            m = alpha > 0
            values.append(np.abs(img - prev)[m].mean() / img[m].mean())
        prev = img
    if not quiet:
        print("%.5f" % np.mean(values))
    return np.mean(values)


def disocclusion(out, ref, fr):
    new, old = [], []
    for f in fr[1:]:
        r, g, b, h = channels(frame_path(out, f), ["indirect.R", "indirect.G", "indirect.B",
                                                   "history.Y"])
        lay = "ViewLayer."
        c = channels(frame_path(ref, f), [lay + "DiffCol." + k for k in "RGB"] +
                     [lay + "DiffInd." + k for k in "RGB"] + [lay + "Depth.Z"])
        ref_ind = np.stack([c[0] * c[3], c[1] * c[4], c[2] * c[5]], -1)
        err = (np.stack([r, g, b], -1) - ref_ind) ** 2
        geo = c[6] < 1e9
        new.append(err[geo & (h == 1)])
        old.append(err[geo & (h > 1)])
    new, old = np.concatenate(new), np.concatenate(old)
    print("%.4f %.4f %.2f" % (np.sqrt(new.mean()) if new.size else float("nan"),
                              np.sqrt(old.mean()), 100.0 * new.shape[0] /
                              (new.shape[0] + old.shape[0])))


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "flicker":
        flicker(sys.argv[2], frames(sys.argv[3]))
    elif len(sys.argv) == 5 and sys.argv[1] == "changes":
        a = flicker(sys.argv[2], frames(sys.argv[4]), quiet=True)
        b = flicker(sys.argv[3], frames(sys.argv[4]), "ViewLayer.Combined.", quiet=True)
        print("%.4f %.4f %.2f" % (a, b, a / b))
    elif len(sys.argv) == 5 and sys.argv[1] == "disocclusion":
        disocclusion(sys.argv[2], sys.argv[3], frames(sys.argv[4]))
    else:
        raise SystemExit(__doc__)
