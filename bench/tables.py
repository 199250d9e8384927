#!/usr/bin/env python3
"""Markdown table rows from the bench.json that `hbil bench` writes (bench/tables.sh).

    tables.py DIR [--prefix TEXT] [--label CONFIG=TEXT ...] COLUMN...

One row per configuration of DIR/bench.json, in its order: the prefix cell (if any), the
label (CONFIG's text, else the configuration's name; --label CONFIG::TEXT where
CONFIG holds an "="), then one or more cells per COLUMN:

    s                seconds per frame (median of the timed runs)
    REF:rmp          RMSE / mean error / PSNR of reference REF (its --ref name)
    REF:psnr         PSNR
    REF:rel          relative RMSE / energy share (%)
    REF:frames       PSNR frame by frame, " / "-joined
    REF:change       frame-to-frame change of hbil's layer (a static camera's flicker)
    REF:changes      change of hbil's layer / of the reference / their ratio
    revealed         RMSE on newly revealed pixels | elsewhere | their share (%) (--stability)
    cuts             the frames where a cut was detected, and why
    speedup          the equal-error speedup against the renders (--render)

Every figure is bench's own; nothing is computed here but the formatting.
"""
import json
import sys


def fmt(v, spec):
    return "n/a" if v is None else spec % v


def cells(c, col):
    if col == "s":
        return ["%.3f" % c["seconds_per_frame"]]
    if col == "revealed":
        s = c["stability"]
        return ["%.4f" % s["revealed_rmse"], "%.4f" % s["other_rmse"],
                "%.2f" % (100 * s["revealed_share"])]
    if col == "cuts":
        return ["; ".join("frame %d: %s" % (k["frame"], k["reason"]) for k in c["cuts"]) or "none"]
    if col == "speedup":
        v = c.get("equal_error_speedup")
        return ["-" if v is None else "%s%.1fx" % (c.get("equal_error_speedup_bound", ""), v)]
    ref, _, what = col.rpartition(":")
    L = c["layers"][ref]
    if what == "rmp":
        return ["%.4f / %+.4f / %.2f" % (L["rmse"], L["mean_error"], L["psnr"])]
    if what == "psnr":
        return ["%.2f" % L["psnr"]]
    if what == "rel":
        return ["%.3f / %.0f" % (L["relative_rmse"], 100 * L["energy"])]
    if what == "frames":
        return [" / ".join(fmt(v, "%.2f") for v in L["psnr_per_frame"])]
    if what == "change":
        return [fmt(L["change"], "%.5f")]
    if what == "changes":
        a, b = L["change"], L["reference_change"]
        return ["%s / %s / %s" % (fmt(a, "%.4f"), fmt(b, "%.4f"),
                                  "n/a" if not a or not b else "%.2f" % (a / b))]
    raise SystemExit("tables.py: unknown column " + col)


def main(argv):
    if len(argv) < 2:
        raise SystemExit(__doc__)
    d, args = argv[1], argv[2:]
    prefix, labels, cols = None, {}, []
    i = 0
    while i < len(args):
        if args[i] == "--prefix":
            prefix, i = args[i + 1], i + 2
        elif args[i] == "--label":
            a = args[i + 1]
            k, _, v = a.partition("::") if "::" in a else a.partition("=")
            labels[k], i = v, i + 2
        else:
            cols.append(args[i])
            i += 1
    j = json.load(open(d + "/bench.json"))
    for c in j["configurations"]:
        row = ([prefix] if prefix is not None else []) + [labels.get(c["name"], c["name"])]
        for col in cols:
            row += cells(c, col)
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main(sys.argv)
