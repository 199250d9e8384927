#!/usr/bin/env python3
"""Repack Blender multilayer EXRs to save space, keeping names and header attributes.

    python3 samples/blender/repack_exr.py FILE.exr [FILE.exr ...]
    python3 samples/blender/repack_exr.py --drop Combined FILE.exr ...  # also drop a pass
    python3 samples/blender/repack_exr.py --check FILE.exr   # only print channel types

Channels ``*.Depth.Z`` and ``*.Position.*`` stay 32-bit FLOAT, every other
channel becomes HALF.  Output: single part, scanline, ZIP compression.  The
channel names and all header attributes of the input are kept (Blender's
``BlenderMultiChannel`` marker, stamp strings, ``cycles.*`` statistics...).
``--drop PASS`` (repeatable) removes the channels ``<layer>.PASS.*`` (used for
the 1-bounce reference, where Blender always writes Combined although the pass
is switched off).  Files are rewritten in place (through a temporary file); a
file that already has the target layout is left alone.

Needs the python3 OpenImageIO bindings (Debian: python3-openimageio) and numpy.
"""
import os
import sys

import numpy as np
import OpenImageIO as oiio

FLOAT_SUFFIXES = (".Depth.Z",)
FLOAT_INFIXES = (".Position.",)


def wants_float(name):
    return name.endswith(FLOAT_SUFFIXES) or any(s in name for s in FLOAT_INFIXES) \
        or name in ("Z", "Depth.Z")


def target_formats(names):
    return [oiio.TypeFloat if wants_float(n) else oiio.TypeHalf for n in names]


def channel_formats(spec):
    if len(spec.channelformats):
        return [str(t) for t in spec.channelformats]
    return [str(spec.format)] * spec.nchannels


def dropped(name, drop):
    parts = name.split(".")
    return len(parts) >= 3 and parts[-2] in drop


def repack(path, drop=()):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise RuntimeError("cannot open %s: %s" % (path, oiio.geterror()))
    if inp.seek_subimage(1, 0):
        inp.close()
        raise RuntimeError("%s has several parts; expected a single-part multilayer EXR" % path)
    inp.seek_subimage(0, 0)
    spec = inp.spec()
    all_names = list(spec.channelnames)
    keep = [i for i, n in enumerate(all_names) if not dropped(n, drop)]
    names = [all_names[i] for i in keep]
    want = target_formats(names)
    have = channel_formats(spec)
    comp = spec.get_string_attribute("compression", "")
    if len(keep) == len(all_names) and have == [str(t) for t in want] and comp == "zip" \
            and spec.tile_width == 0:
        inp.close()
        return False
    pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    inp.close()
    if pixels is None:
        raise RuntimeError("cannot read %s: %s" % (path, oiio.geterror()))
    pixels = np.ascontiguousarray(pixels[..., keep])

    out_spec = oiio.ImageSpec(spec)  # copies channel names, windows and all attributes
    if len(keep) != len(all_names):
        out_spec.nchannels = len(keep)
        out_spec.channelnames = tuple(names)
        out_spec.alpha_channel = -1
        out_spec.z_channel = -1
    out_spec.set_format(oiio.FLOAT)
    out_spec.channelformats = tuple(want)
    out_spec.tile_width = out_spec.tile_height = out_spec.tile_depth = 0
    out_spec.attribute("compression", "zip")
    # OIIO-internal hints that must not reach the new header
    for a in ("oiio:BitsPerSample", "oiio:subimages", "oiio:subimagename"):
        out_spec.erase_attribute(a)

    tmp = path + ".repack.tmp.exr"
    write_float_image(tmp, out_spec, pixels)
    verify(path, tmp, pixels, names)
    os.replace(tmp, path)
    return True


def write_float_image(tmp, spec, pixels):
    """Write ``pixels`` (float32, height x width x channels) to ``tmp`` with ``spec``."""
    out = oiio.ImageOutput.create(tmp)
    if out is None or not out.open(tmp, spec):
        raise RuntimeError("cannot write %s: %s" % (tmp, oiio.geterror()))
    ok = out.write_image(np.ascontiguousarray(pixels, dtype=np.float32))
    out.close()
    if not ok:
        raise RuntimeError("write failed %s: %s" % (tmp, out.geterror()))


def set_windows(path, x, y, full_width, full_height):
    """Rewrite ``path`` in place with its data window at (x, y) and a display window of
    full_width x full_height at (0, 0): an overscan render (samples/blender --overscan), whose
    guard band lies outside the display window. Pixels, channel names and types, compression
    and attributes stay as they are."""
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise RuntimeError("cannot open %s: %s" % (path, oiio.geterror()))
    spec = inp.spec()
    pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    inp.close()
    if pixels is None:
        raise RuntimeError("cannot read %s: %s" % (path, oiio.geterror()))
    out_spec = oiio.ImageSpec(spec)
    out_spec.x, out_spec.y = x, y
    out_spec.full_x = out_spec.full_y = 0
    out_spec.full_width, out_spec.full_height = full_width, full_height
    for a in ("oiio:BitsPerSample", "oiio:subimages", "oiio:subimagename"):
        out_spec.erase_attribute(a)
    tmp = path + ".window.tmp.exr"
    write_float_image(tmp, out_spec, pixels)
    check = oiio.ImageInput.open(tmp)
    s2 = check.spec()
    again = check.read_image(0, 0, 0, s2.nchannels, oiio.FLOAT)
    check.close()
    if (s2.x, s2.y, s2.full_width, s2.full_height) != (x, y, full_width, full_height) \
            or channel_formats(s2) != channel_formats(spec) \
            or not np.array_equal(again, pixels, equal_nan=True):
        raise RuntimeError("%s: the windowed copy does not match" % path)
    os.replace(tmp, path)


def verify(src_path, new_path, src_pixels, src_names):
    """Re-read the new file: same names, expected types, values within half precision."""
    src = oiio.ImageInput.open(src_path)
    s_spec = src.spec()
    src.close()
    inp = oiio.ImageInput.open(new_path)
    spec = inp.spec()
    px = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    inp.close()
    names = list(spec.channelnames)
    if names != list(src_names):
        raise RuntimeError("channel names changed in %s" % new_path)
    if channel_formats(spec) != [str(t) for t in target_formats(names)]:
        raise RuntimeError("channel types not as intended in %s: %s"
                           % (new_path, channel_formats(spec)))
    for i, n in enumerate(names):
        a = src_pixels[..., i]
        b = px[..., i]
        if wants_float(n):
            if not np.array_equal(a, b):
                raise RuntimeError("float channel %s changed" % n)
        else:
            fin = np.isfinite(a) & (np.abs(a) < 65504)
            ref = a[fin].astype(np.float16).astype(np.float32)
            if not np.array_equal(ref, b[fin]):
                raise RuntimeError("half channel %s not a plain float->half rounding" % n)
    old_attrs = {a.name for a in s_spec.extra_attribs}
    new_attrs = {a.name for a in spec.extra_attribs}
    lost = sorted(old_attrs - new_attrs - {"oiio:subimages"})
    if lost:
        raise RuntimeError("attributes lost in %s: %s" % (new_path, lost))


def main(argv):
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if argv else 2
    check = argv[0] == "--check"
    files = argv[1:] if check else list(argv)
    drop = []
    while "--drop" in files:
        i = files.index("--drop")
        drop.append(files[i + 1])
        del files[i:i + 2]
    rc = 0
    for f in files:
        try:
            if check:
                inp = oiio.ImageInput.open(f)
                s = inp.spec()
                inp.close()
                for n, t in zip(s.channelnames, channel_formats(s)):
                    print("%s\t%s\t%s" % (f, n, t))
                continue
            before = os.path.getsize(f)
            changed = repack(f, tuple(drop))
            after = os.path.getsize(f)
            print("%s: %s %d -> %d bytes" % (f, "repacked" if changed else "already packed",
                                             before, after))
        except Exception as e:  # report and go on with the other files
            print("ERROR %s: %s" % (f, e), file=sys.stderr)
            rc = 1
    return rc


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
