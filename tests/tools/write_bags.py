#!/usr/bin/python3
"""Writes ROS 1 bags of dvs_msgs/EventArray (and sensor_msgs/Image) from an ECD text folder, with
Debian's python3-rosbag and message classes that genpy generates from the message definitions.
Test input for eds's own bag reader: the two never share code.

usage: write_bags.py SEQUENCE_DIR OUT_DIR MAX_EVENTS EVENTS_PER_MESSAGE
writes OUT_DIR/events_{none,bz2,lz4}.bag
"""
import gzip
import sys

import genpy.dynamic
import rosbag
import rospy

HEADER = """uint32 seq
time stamp
string frame_id
"""
EVENT_ARRAY = """std_msgs/Header header
uint32 height
uint32 width
Event[] events
================================================================================
MSG: std_msgs/Header
""" + HEADER + """================================================================================
MSG: dvs_msgs/Event
uint16 x
uint16 y
time ts
bool polarity
"""


def stamp(t_text):
    """An ECD time ('12.345678901' s) as a rospy.Time, exactly (no float on the way)."""
    sec, _, frac = t_text.partition(".")
    return rospy.Time(int(sec), int((frac + "000000000")[:9]))


def main():
    seq_dir, out_dir, max_events, per_msg = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    classes = genpy.dynamic.generate_dynamic("dvs_msgs/EventArray", EVENT_ARRAY)
    EventArray, Event = classes["dvs_msgs/EventArray"], classes["dvs_msgs/Event"]
    events = []
    with gzip.open(seq_dir + "/events.txt.gz", "rt") as f:
        for line in f:
            if len(events) >= max_events:
                break
            t, x, y, p = line.split()
            events.append(Event(x=int(x), y=int(y), ts=stamp(t), polarity=p == "1"))
    for compression in ("none", "bz2", "lz4"):
        with rosbag.Bag(f"{out_dir}/events_{compression}.bag", "w", compression=compression,
                        chunk_threshold=64 * 1024) as bag:
            for seq, i in enumerate(range(0, len(events), per_msg)):
                msg = EventArray(width=240, height=180, events=events[i:i + per_msg])
                msg.header.seq = seq
                msg.header.stamp = msg.events[-1].ts
                bag.write("/dvs/events", msg, t=msg.header.stamp)


if __name__ == "__main__":
    main()
