#!/usr/bin/python3
"""Writes an ECD text folder in the HDF5 layouts other datasets publish, with Debian's python3-h5py:
test input for eds's HDF5 readers (they share no code with this script).

usage: write_hdf5_layouts.py SEQUENCE_DIR OUT_DIR UNTIL_S
       write_hdf5_layouts.py --us-folders SEQUENCE_DIR OUT_DIR UNTIL_S
writes, up to UNTIL_S,
OUT_DIR/mvsec.h5: davis/left/events (N x 4 float64: x, y, t [s], p -1/+1),
  davis/left/image_raw (N x H x W uint8), davis/left/image_raw_ts (N float64 [s]);
OUT_DIR/m3ed.h5: prophesee/left/{x, y (uint16), t (int64 us), p (int8 0/1), ms_map_idx (uint64)},
  ovc/left/data (N x H x W x 1 uint8), ovc/ts (N int64 us);
OUT_DIR/vector.h5: VECtor's DSEC-style layout, every dataset Zstandard-compressed (HDF5 filter 32015):
  events/{x, y (uint16), p (uint8), t (uint32 us after t_offset)}, ms_to_idx (uint64), t_offset (int64, (1,)).
  h5py stores the chunks as they are, compressed by Debian's `zstd` program (no zstd plugin needed);
  OUT_DIR/vector_corrupt.h5 the same with its first events/t chunk not zstd.
"""
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np
from PIL import Image

from esim_text import events_us, text_events


def write_us_folders(seq_dir, out_dir, until):
    """The sequence with its event times cut to the microsecond, as folders sharing its frames, calibration
    and ground truth: OUT_DIR/us_text (events.txt), OUT_DIR/us_dsec (events.h5 in DSEC's layout: int64 us
    after t_offset, ms_to_idx), OUT_DIR/us_vector (VECtor's: uint32 us, zstd), so that a run over each
    must give the same outputs."""
    rows = events_us(seq_dir, until)
    ev = np.array(rows, dtype=np.int64)
    for name in ("us_text", "us_dsec", "us_vector"):
        d = os.path.join(out_dir, name)
        os.makedirs(d, exist_ok=True)
        for f in ("images.txt", "calib.txt", "groundtruth.txt"):
            shutil.copy(os.path.join(seq_dir, f), d)
        if not os.path.exists(os.path.join(d, "images")):
            os.symlink(os.path.abspath(os.path.join(seq_dir, "images")), os.path.join(d, "images"))
    with open(os.path.join(out_dir, "us_text/events.txt"), "w") as f:
        for t, x, y, p in rows:
            f.write(f"{t // 1_000_000}.{t % 1_000_000:06d} {x} {y} {p}\n")
    t_offset = int(ev[0, 0])
    rel = ev[:, 0] - t_offset
    with h5py.File(os.path.join(out_dir, "us_dsec/events.h5"), "w") as h:
        h["events/x"], h["events/y"] = ev[:, 1].astype(np.uint16), ev[:, 2].astype(np.uint16)
        h["events/t"], h["events/p"] = rel, ev[:, 3].astype(np.uint8)
        h["ms_to_idx"] = np.searchsorted(rel, np.arange(0, rel[-1] // 1000 + 2) * 1000).astype(np.uint64)
        h["t_offset"] = np.int64(t_offset)
    pm = np.where(ev[:, 3] > 0, 1.0, -1.0)
    write_vector(os.path.join(out_dir, "us_vector/events.h5"), np.stack([ev[:, 1], ev[:, 2], ev[:, 0], pm], 1),
                 ev[:, 0])


def main():
    if sys.argv[1] == "--us-folders":
        write_us_folders(sys.argv[2], sys.argv[3], float(sys.argv[4]))
        return
    seq_dir, out_dir, until = sys.argv[1], sys.argv[2], float(sys.argv[3])
    rows = [(float(x), float(y), float(t), 1.0 if p == 1 else -1.0) for t, x, y, p in text_events(seq_dir, until)]
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
    ev = np.array(rows, dtype=np.float64)
    t_us = np.array([int(round(t * 1e9)) // 1000 for t in ev[:, 2]], dtype=np.int64)
    with h5py.File(out_dir + "/m3ed.h5", "w") as h:
        left = h.create_group("prophesee").create_group("left")
        left.create_dataset("x", data=ev[:, 0].astype(np.uint16))
        left.create_dataset("y", data=ev[:, 1].astype(np.uint16))
        left.create_dataset("t", data=t_us)
        left.create_dataset("p", data=(ev[:, 3] > 0).astype(np.int8))
        ms = np.searchsorted(t_us, np.arange(0, t_us[-1] // 1000 + 2) * 1000).astype(np.uint64)
        left.create_dataset("ms_map_idx", data=ms)
        ovc = h.create_group("ovc")
        ovc.create_group("left").create_dataset("data", data=np.stack(images)[..., None])
        ovc.create_dataset("ts", data=np.array([int(round(s * 1e6)) for s in stamps], dtype=np.int64))
    write_vector(out_dir + "/vector.h5", ev, t_us)
    write_m3ed_calibrated(out_dir + "/m3ed_calibrated.h5", ev, t_us, images, stamps)
    write_vector(out_dir + "/vector_corrupt.h5", ev[:20000], t_us[:20000], corrupt=True)


def write_m3ed_calibrated(path, ev, t_us, images, stamps):
    """M3ED with its calibration groups: the event camera's (prophesee/left/calib) and the OVC imager's,
    2 cm beside it (T_to_prophesee_left), whose frames therefore are another camera's."""
    with h5py.File(path, "w") as h:
        left = h.create_group("prophesee/left")
        for name, data in (("x", ev[:, 0].astype(np.uint16)), ("y", ev[:, 1].astype(np.uint16)), ("t", t_us),
                           ("p", (ev[:, 3] > 0).astype(np.int8))):
            left.create_dataset(name, data=data)
        for group, k in (("prophesee/left/calib", [199.092, 198.829, 132.192, 110.712]),
                         ("ovc/left/calib", [200.0, 200.0, 120.0, 90.0])):
            c = h.create_group(group)
            c["intrinsics"] = np.array(k)
            c["resolution"] = np.array([240, 180])
            c["distortion_model"] = "radtan"
            c["distortion_coeffs"] = np.array([-0.368436311798, 0.150947243557, -0.000296130534, -0.000759431524])
            T = np.eye(4)
            T[0, 3] = 0.02 if group.startswith("ovc") else 0.0
            c["T_to_prophesee_left"] = T
        h["ovc/left/data"] = np.stack(images)[..., None]
        h["ovc/ts"] = np.array([int(round(s * 1e6)) for s in stamps], dtype=np.int64)


def zstd_dataset(h, name, data, chunk=10000, sized=False, corrupt=False):
    """A dataset compressed with HDF5 filter 32015, its chunks written as the zstd program made them
    (with the size in each frame's header when `sized`; the first chunk garbage when `corrupt`)."""
    chunk = min(chunk, len(data))
    ds = h.create_dataset(name, shape=data.shape, dtype=data.dtype, chunks=(chunk,), compression=32015,
                          allow_unknown_filter=True)
    for start in range(0, len(data), chunk):
        block = np.zeros(chunk, dtype=data.dtype)
        part = data[start:start + chunk]
        block[:len(part)] = part
        size = [f"--stream-size={block.nbytes}"] if sized else []
        packed = subprocess.run(["zstd", "-q", "-c"] + size, input=block.tobytes(), stdout=subprocess.PIPE,
                                check=True).stdout
        ds.id.write_direct_chunk((start,), b"not zstd" if corrupt and start == 0 else packed)


def write_vector(path, ev, t_us, corrupt=False):
    t_offset = int(t_us[0])
    rel = t_us - t_offset
    with h5py.File(path, "w") as h:
        zstd_dataset(h, "events/x", ev[:, 0].astype(np.uint16), sized=True)
        zstd_dataset(h, "events/y", ev[:, 1].astype(np.uint16))
        zstd_dataset(h, "events/p", (ev[:, 3] > 0).astype(np.uint8))
        zstd_dataset(h, "events/t", rel.astype(np.uint32), corrupt=corrupt)
        ms = np.searchsorted(rel, np.arange(0, rel[-1] // 1000 + 2) * 1000).astype(np.uint64)
        zstd_dataset(h, "ms_to_idx", ms, chunk=100)
        h.create_dataset("t_offset", data=np.array([t_offset], dtype=np.int64))


if __name__ == "__main__":
    main()
