#!/usr/bin/env python3
"""Copy the BackFaces.Depth.Z channel of back-face renders into main frames.

    python3 samples/blender/merge_backdepth.py MAIN_DIR BACK_DIR

For every MAIN_DIR/frame_####.exr with a BACK_DIR/frame_####.exr (rendered with
``--mode backfaces``), rewrites the main frame with the channel BackFaces.Depth.Z (32-bit
float) added, or replaced when it is already there. Every other channel is copied unchanged
(same names, same pixel types, bit for bit) and so are the header attributes; the file is
written through a temporary file and checked before it replaces the original.

Needs the python3 OpenImageIO bindings (Debian: python3-openimageio) and numpy.
"""
import glob
import os
import sys

import numpy as np
import OpenImageIO as oiio

CHANNEL = "BackFaces.Depth.Z"


def read_all(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise SystemExit("cannot open %s: %s" % (path, oiio.geterror()))
    spec = inp.spec()
    # Read channel by channel in float; halves go back to half exactly.
    data = [inp.read_image(0, 0, c, c + 1, oiio.FLOAT).reshape(spec.height, spec.width)
            for c in range(spec.nchannels)]
    inp.close()
    return spec, data


def formats(spec):
    if len(spec.channelformats):
        return list(spec.channelformats)
    return [spec.format] * spec.nchannels


def merge(main_path, back_path):
    spec, data = read_all(main_path)
    bspec, bdata = read_all(back_path)
    names, fmts = list(spec.channelnames), formats(spec)
    if CHANNEL not in bspec.channelnames:
        raise SystemExit("%s has no channel %s" % (back_path, CHANNEL))
    if (bspec.width, bspec.height) != (spec.width, spec.height):
        raise SystemExit("%s and %s differ in size" % (main_path, back_path))
    back = bdata[list(bspec.channelnames).index(CHANNEL)]
    if CHANNEL in names:
        k = names.index(CHANNEL)
        data[k] = back
    else:
        # Before the first channel that sorts after it (OpenImageIO presents R, G, B, A in that
        # order, not the file's alphabetical one, so the list is not sorted as a whole).
        k = next((k for k, n in enumerate(names) if n > CHANNEL), len(names))
        names.insert(k, CHANNEL)
        fmts.insert(k, oiio.TypeFloat)
        data.insert(k, back)
    out_spec = oiio.ImageSpec(spec)
    out_spec.nchannels = len(names)
    out_spec.channelnames = names
    out_spec.channelformats = fmts
    out_spec.alpha_channel = -1
    out_spec.z_channel = -1
    tmp = main_path + ".tmp.exr"
    out = oiio.ImageOutput.create(tmp)
    if out is None or not out.open(tmp, out_spec):
        raise SystemExit("cannot write %s: %s" % (tmp, oiio.geterror()))
    pixels = np.stack(data, axis=-1).astype(np.float32)
    if not out.write_image(pixels):
        raise SystemExit("cannot write %s: %s" % (tmp, out.geterror()))
    out.close()
    # Check: every channel reads back as written (halves exactly, being halves already).
    cspec, cdata = read_all(tmp)
    assert list(cspec.channelnames) == names, (cspec.channelnames, names)
    for k in range(len(names)):
        if not np.array_equal(cdata[k], data[k].astype(np.float32), equal_nan=True):
            os.remove(tmp)
            raise SystemExit("%s: channel %s changed on write" % (main_path, names[k]))
    os.replace(tmp, main_path)
    valid = back < 1e9
    print("%s: + %s (%.0f%% of pixels see a back face)"
          % (main_path, CHANNEL, 100.0 * valid.mean()), flush=True)


def main(argv):
    if len(argv) != 3:
        raise SystemExit(__doc__)
    main_dir, back_dir = argv[1], argv[2]
    frames = sorted(glob.glob(os.path.join(main_dir, "frame_*.exr")))
    done = 0
    for f in frames:
        b = os.path.join(back_dir, os.path.basename(f))
        if os.path.exists(b):
            merge(f, b)
            done += 1
    if done == 0:
        raise SystemExit("no frame of %s has a back-face render in %s" % (main_dir, back_dir))


if __name__ == "__main__":
    main(sys.argv)
