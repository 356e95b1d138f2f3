#!/usr/bin/python3
"""Writes ESIM events as a Prophesee .dat CD file with NumPy, as Prophesee documents the format
(openeb's dat_tools): '% ' header lines, then event type (12, CD) and size (8) bytes, then records of
uint32 t (us) and uint32 x | y << 14 | p << 28, little-endian.

usage: write_dat.py SEQ_DIR OUT.dat UNTIL_S [--type T] [--size S] [--width W]"""
import sys

import numpy as np

from esim_text import events_us


def main():
    seq_dir, out, until = sys.argv[1], sys.argv[2], float(sys.argv[3])
    opts = dict(zip(sys.argv[4::2], sys.argv[5::2]))
    a = np.array(events_us(seq_dir, until), dtype=np.int64)
    rec = np.zeros(len(a), dtype=[("t", "<u4"), ("_", "<u4")])
    rec["t"] = a[:, 0]
    rec["_"] = a[:, 1] | (a[:, 2] << 14) | (a[:, 3] << 28)
    width = opts.get("--width", "240")
    header = f"% Data file containing CD events.\n% Version 2\n% Date 2026-11-26 12:00:00\n% Height 180\n% Width {width}\n"
    with open(out, "wb") as f:
        f.write(header.encode())
        f.write(bytes([int(opts.get("--type", 12)), int(opts.get("--size", 8))]))
        f.write(rec.tobytes())


if __name__ == "__main__":
    main()
