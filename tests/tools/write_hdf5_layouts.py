#!/usr/bin/python3
"""Writes an ECD text folder in the HDF5 layouts other datasets publish, with Debian's python3-h5py:
test input for eds's HDF5 readers (they share no code with this script).

usage: write_hdf5_layouts.py SEQUENCE_DIR OUT_DIR UNTIL_S
writes OUT_DIR/mvsec.h5: davis/left/events (N x 4 float64: x, y, t [s], p -1/+1),
davis/left/image_raw (N x H x W uint8), davis/left/image_raw_ts (N float64 [s]), up to UNTIL_S.
"""
import gzip
import sys

import h5py
import numpy as np
from PIL import Image


def main():
    seq_dir, out_dir, until = sys.argv[1], sys.argv[2], float(sys.argv[3])
    rows = []
    with gzip.open(seq_dir + "/events.txt.gz", "rt") as f:
        for line in f:
            t, x, y, p = line.split()
            if float(t) > until:
                break
            rows.append((float(x), float(y), float(t), 1.0 if p == "1" else -1.0))
    images, stamps = [], []
    with open(seq_dir + "/images.txt") as f:
        for line in f:
            t, path = line.split()
            if float(t) > until:
                break
            images.append(np.asarray(Image.open(seq_dir + "/" + path).convert("L"), dtype=np.uint8))
            stamps.append(float(t))
    with h5py.File(out_dir + "/mvsec.h5", "w") as h:
        left = h.create_group("davis").create_group("left")
        left.create_dataset("events", data=np.array(rows, dtype=np.float64), chunks=(4096, 4), compression="gzip")
        left.create_dataset("image_raw", data=np.stack(images), compression="gzip")
        left.create_dataset("image_raw_ts", data=np.array(stamps, dtype=np.float64))


if __name__ == "__main__":
    main()
