#!/usr/bin/python3
"""Writes a large ROS 1 bag of dvs_msgs/EventArray messages with Debian's python3-rosbag, for reader
benchmarks: random events at 240x180, 50,000 per message, times increasing by 1 us per 100 events.
Payloads are packed with NumPy and written raw (rosbag still frames records, chunks and the index).

usage: write_big_bag.py OUT.bag MEGABYTES COMPRESSION(none|lz4|bz2)"""
import sys

import genpy.dynamic
import numpy as np
import rosbag
import rospy

DEFINITION = ("std_msgs/Header header\nuint32 height\nuint32 width\nEvent[] events\n" + "=" * 80 +
              "\nMSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n" + "=" * 80 +
              "\nMSG: dvs_msgs/Event\nuint16 x\nuint16 y\ntime ts\nbool polarity\n")
EVENT = np.dtype([("x", "<u2"), ("y", "<u2"), ("sec", "<u4"), ("nsec", "<u4"), ("p", "u1")])


def main():
    out, megabytes, compression = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    per_msg = 50_000
    messages = megabytes * 1_000_000 // (per_msg * EVENT.itemsize)
    rng = np.random.default_rng(1)
    cls = genpy.dynamic.generate_dynamic("dvs_msgs/EventArray", DEFINITION)["dvs_msgs/EventArray"]
    with rosbag.Bag(out, "w", compression=compression) as bag:
        for k in range(messages):
            ev = np.zeros(per_msg, dtype=EVENT)
            ev["x"] = rng.integers(0, 240, per_msg)
            ev["y"] = rng.integers(0, 180, per_msg)
            t_ns = 1_000_000_000 + (k * per_msg + np.arange(per_msg)) // 100 * 1000
            ev["sec"], ev["nsec"] = t_ns // 1_000_000_000, t_ns % 1_000_000_000
            ev["p"] = rng.integers(0, 2, per_msg)
            last = rospy.Time(int(ev["sec"][-1]), int(ev["nsec"][-1]))
            header = np.array([k, last.secs, last.nsecs, 0], dtype="<u4").tobytes()  # seq, stamp, frame_id ""
            body = header + np.array([180, 240, per_msg], dtype="<u4").tobytes() + ev.tobytes()
            bag.write("/dvs/events", ("dvs_msgs/EventArray", body, cls._md5sum, cls), t=last, raw=True)


if __name__ == "__main__":
    main()
