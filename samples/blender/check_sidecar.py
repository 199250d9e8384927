#!/usr/bin/env python3
"""Check a camera sidecar against the Position / Depth passes of its frame.

    python3 samples/blender/check_sidecar.py samples/room_poles/frame_0001.exr [...]

For every geometry pixel away from silhouettes (depth smooth over 3x3 and
unit-length normal), the world-space ``Position`` is projected with the
sidecar camera and compared with the pixel centre; ``-z_camera`` is compared
with ``Depth.Z`` (planar depth).  Prints median / 95th percentile / max of the
reprojection error in pixels and of the relative depth error.  Exit status 1
when the median error exceeds 0.5 px.

Camera model (PERSP, Blender):  p_cam = inverse(matrix_world) * p_world; the
camera looks down -Z with +Y up.  Sensor fit AUTO uses sensor_width on the
larger image side (HORIZONTAL / VERTICAL force width / height); focal in
pixels f = lens_mm / sensor_mm * size_px.  Raster (x right, y up, pixel
centres at i + 0.5): x = w/2 + shift_x*max(w,h) + f * X / -Z,
y = h/2 + shift_y*max(w,h) + f * aspect * Y / -Z.  EXR rows run top-down, so
row + 0.5 = h - y.
"""
import json
import os
import sys

import numpy as np
import OpenImageIO as oiio


def load_exr(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise SystemExit("cannot open %s" % path)
    spec = inp.spec()
    px = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    inp.close()
    return {n: px[..., i] for i, n in enumerate(spec.channelnames)}


def intrinsics(cam):
    w, h = cam["resolution"]
    pa = cam["pixel_aspect"]  # pixel_aspect_y / pixel_aspect_x
    fit = cam["sensor_fit"]
    if fit == "AUTO":
        fit = "HORIZONTAL" if w >= h * pa else "VERTICAL"
        sensor = cam["sensor_width_mm"]
    else:
        sensor = cam["sensor_width_mm"] if fit == "HORIZONTAL" else cam["sensor_height_mm"]
    if fit == "HORIZONTAL":
        fx = cam["lens_mm"] / sensor * w
        fy = fx / pa
    else:
        fy = cam["lens_mm"] / sensor * h
        fx = fy * pa
    m = max(w, h)
    cx = w / 2.0 + cam["shift_x"] * m
    cy = h / 2.0 + cam["shift_y"] * m
    return fx, fy, cx, cy


def check(exr):
    side = os.path.splitext(exr)[0] + ".camera.json"
    with open(side) as f:
        cam = json.load(f)
    assert cam["format"] == "hbil-camera-1", cam["format"]
    assert cam["type"] == "PERSP", "only PERSP is checked"
    ch = load_exr(exr)
    L = "ViewLayer."
    P = np.stack([ch[L + "Position." + c] for c in "XYZ"], -1).astype(np.float64)
    N = np.stack([ch[L + "Normal." + c] for c in "XYZ"], -1).astype(np.float64)
    D = ch[L + "Depth.Z"].astype(np.float64)
    h, w = D.shape
    assert [w, h] == cam["resolution"], (w, h, cam["resolution"])

    # interior pixels: geometry, smooth depth, unit normal
    geo = D < 1e9
    pad = np.pad(D, 1, mode="edge")
    nb = np.stack([pad[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]
                   for dy in (-1, 0, 1) for dx in (-1, 0, 1)])
    smooth = (nb.max(0) - nb.min(0)) < 0.02 * D
    unit = np.abs(np.linalg.norm(N, axis=-1) - 1.0) < 1e-3
    ok = geo & smooth & unit
    ok[0, :] = ok[-1, :] = ok[:, 0] = ok[:, -1] = False

    M = np.array(cam["matrix_world"], dtype=np.float64)
    V = np.linalg.inv(M)
    rows, cols = np.nonzero(ok)
    Pw = P[rows, cols]
    Pc = Pw @ V[:3, :3].T + V[:3, 3]
    fx, fy, cx, cy = intrinsics(cam)
    zf = -Pc[:, 2]
    x = cx + fx * Pc[:, 0] / zf
    y = cy + fy * Pc[:, 1] / zf
    col_pred = x - 0.5
    row_pred = (h - y) - 0.5
    err = np.hypot(col_pred - cols, row_pred - rows)
    derr = np.abs(zf - D[rows, cols]) / D[rows, cols]
    res = {"file": exr, "pixels": int(ok.sum()),
           "reproj_px_median": float(np.median(err)),
           "reproj_px_p95": float(np.percentile(err, 95)),
           "reproj_px_max": float(err.max()),
           "mean_dx": float(np.mean(col_pred - cols)), "mean_dy": float(np.mean(row_pred - rows)),
           "depth_rel_median": float(np.median(derr)),
           "depth_rel_max": float(derr.max())}
    return res


def main(argv):
    rc = 0
    for exr in argv:
        r = check(exr)
        print("%s: %d px  reprojection median %.3f px  p95 %.3f px  max %.3f px  "
              "bias (%.3f, %.3f) px  depth rel err median %.1e max %.1e"
              % (os.path.basename(r["file"]), r["pixels"], r["reproj_px_median"],
                 r["reproj_px_p95"], r["reproj_px_max"], r["mean_dx"], r["mean_dy"],
                 r["depth_rel_median"], r["depth_rel_max"]))
        if r["reproj_px_median"] > 0.5:
            rc = 1
    return rc


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
