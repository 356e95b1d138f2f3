#!/usr/bin/python3
"""Writes the binary seeds of the fuzz targets into OUT_DIR/<target>/ at fuzz time: tiny ROS 1 bags
(Debian's python3-rosbag and genpy, three compressions), a rosbag2 SQLite file (python's sqlite3 with a
CDR EventPacket), ROS messages serialized by genpy, EVT 2.0/3.0 words, a PLY file; and, when the
shared samples exist, prefixes of the real AEDAT 4.0, EVT and MCAP recordings (kept out of the
repository).

usage: write_seeds.py OUT_DIR [SHARED_REAL_DIR]
"""
import io
import os
import sqlite3
import struct
import sys

import genpy.dynamic
import rosbag
import rospy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "tools"))
from write_bags import DEFINITIONS  # noqa: E402  (the message definitions the bag tests use)

C = {}
for name, text in DEFINITIONS.items():
    C.update(genpy.dynamic.generate_dynamic(name, text))

# EVT 3.0: TIME_HIGH, TIME_LOW, Y, X_BASE, VECT_12 (three events), X_POS, EXT_TRIGGER.
EVT3_WORDS = [0x8000, 0x6010, 0x0005, 0x3000 | 0x800 | 10, 0x4007, 0x2000 | 0x800 | 20, 0x6020, 0xA001]
# EVT 2.0: a TIME_HIGH, then CD_ON and CD_OFF with 11-bit x / y.
EVT2_WORDS = [(8 << 28) | 1, (1 << 28) | (5 << 22) | (10 << 11) | 20, (0 << 28) | (9 << 22) | (11 << 11) | 21]


def message(name, **fields):
    return C[name](**fields)


def serialized(msg):
    buf = io.BytesIO()
    msg.serialize(buf)
    return buf.getvalue()


def event_packet():
    payload = struct.pack("<%dH" % len(EVT3_WORDS), *EVT3_WORDS)
    return message("event_camera_msgs/EventPacket", height=720, width=1280, seq=1, time_base=0,
                   encoding="evt3", is_bigendian=False, events=payload)


def ros1_messages():
    ev = [C["dvs_msgs/Event"](x=i, y=2 * i, ts=rospy.Time(1, 1000 * i), polarity=i % 2 == 0) for i in range(5)]
    image = message("sensor_msgs/Image", height=18, width=24, encoding="mono8", is_bigendian=0, step=24,
                    data=bytes(i % 256 for i in range(18 * 24)))
    info = message("sensor_msgs/CameraInfo", height=18, width=24, distortion_model="plumb_bob",
                   D=[-0.3, 0.1, 0.0, 0.0, 0.0], K=[20, 0, 12, 0, 20, 9, 0, 0, 1], R=[1, 0, 0, 0, 1, 0, 0, 0, 1],
                   P=[20, 0, 12, 0, 0, 20, 9, 0, 0, 0, 1, 0])
    pose = message("geometry_msgs/PoseStamped")
    pose.pose.orientation.w = 1.0
    return [("/dvs/events", message("dvs_msgs/EventArray", height=18, width=24, events=ev)),
            ("/dvs/image_raw", image), ("/dvs/camera_info", info), ("/optitrack/davis", pose)]


def write_bags(out):
    os.makedirs(out, exist_ok=True)
    for compression in ("none", "lz4", "bz2"):
        with rosbag.Bag(os.path.join(out, "tiny_%s.bag" % compression), "w", compression=compression) as bag:
            for k, (topic, msg) in enumerate(ros1_messages()):
                if hasattr(msg, "header"):
                    msg.header.stamp = rospy.Time(1, 1000 * k)
                bag.write(topic, msg, t=rospy.Time(1, 1000 * k))
    with rosbag.Bag(os.path.join(out, "tiny_packet.bag"), "w") as bag:
        bag.write("/events", event_packet(), t=rospy.Time(1, 0))


def cdr_event_packet():
    """event_camera_msgs/msg/EventPacket in CDR (little-endian encapsulation)."""
    out = bytearray(b"\x00\x01\x00\x00")
    def align(n):
        while (len(out) - 4) % n:
            out.append(0)
    def string(s):
        align(4)
        out.extend(struct.pack("<I", len(s) + 1) + s.encode() + b"\x00")
    out.extend(struct.pack("<iI", 1, 2000))  # header.stamp
    string("camera")                          # header.frame_id
    align(4)
    out.extend(struct.pack("<II", 720, 1280))
    align(8)
    out.extend(struct.pack("<QQ", 1, 0))
    string("evt3")
    out.append(0)  # is_bigendian
    payload = struct.pack("<%dH" % len(EVT3_WORDS), *EVT3_WORDS)
    align(4)
    out.extend(struct.pack("<I", len(payload)) + payload)
    return bytes(out)


def write_db3(out):
    path = os.path.join(out, "tiny.db3")
    if os.path.exists(path):
        os.remove(path)
    db = sqlite3.connect(path)
    db.execute("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
               "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL)")
    db.execute("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
               "timestamp INTEGER NOT NULL, data BLOB NOT NULL)")
    db.execute("INSERT INTO topics VALUES (1, '/events', 'event_camera_msgs/msg/EventPacket', 'cdr', '')")
    for k in range(3):
        db.execute("INSERT INTO messages VALUES (?, 1, ?, ?)", (k + 1, 1000 + k, cdr_event_packet()))
    db.commit()
    db.close()


def write_messages(out):
    os.makedirs(out, exist_ok=True)
    msgs = {m[1]._type: m[1] for m in ros1_messages()}
    msgs["event_camera_msgs/EventPacket"] = event_packet()
    # First byte: bit 0 the serialization (0: ROS 1, 1: CDR), bits 1.. the type (0 Image, 1 CameraInfo,
    # 2 EventPacket), as fuzz_ros_message.cpp reads it.
    for code, name in ((0, "sensor_msgs/Image"), (2, "sensor_msgs/CameraInfo"), (4, "event_camera_msgs/EventPacket")):
        with open(os.path.join(out, name.replace("/", "_")), "wb") as f:
            f.write(bytes([code]) + serialized(msgs[name]))
    with open(os.path.join(out, "cdr_event_packet"), "wb") as f:
        f.write(bytes([5]) + cdr_event_packet())


def write_raw(out):
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "evt3.raw"), "wb") as f:
        f.write(b"% camera_integrator_name Prophesee\n% evt 3.0\n% format EVT3;height=720;width=1280\n% end\n")
        f.write(struct.pack("<%dH" % len(EVT3_WORDS), *EVT3_WORDS))
    with open(os.path.join(out, "evt2.raw"), "wb") as f:
        f.write(b"% evt 2.0\n% geometry 640x480\n% end\n")
        f.write(struct.pack("<%dI" % len(EVT2_WORDS), *EVT2_WORDS))


def write_ply(out):
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "map.ply"), "wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                b"property float z\nproperty float intensity\nend_header\n")
        f.write(struct.pack("<8f", 0.1, 0.2, 1.5, 0.5, -0.3, 0.1, 2.0, 0.25))


def write_prefixes(out, shared):
    """The first bytes of the real recordings: their headers and first packets as seeds."""
    for target, rel, n in (("aedat4", "aedat4/davis346_street.aedat4", 1 << 16),
                           ("prophesee", "prophesee/evt3_gen41_1280x720.raw", 1 << 14),
                           ("prophesee", "prophesee/evt2_gen3_640x480.raw", 1 << 14),
                           ("ros_bag", "ros2_and_ros1_event_camera_msgs/test_events_2/test_events_2_0.mcap", 1 << 16),
                           ("ros_bag", "ros2_and_ros1_event_camera_msgs/test_events_1.bag", 1 << 16)):
        src = os.path.join(shared, rel)
        if not os.path.exists(src):
            continue
        os.makedirs(os.path.join(out, target), exist_ok=True)
        with open(src, "rb") as f, open(os.path.join(out, target, "prefix_" + os.path.basename(rel)), "wb") as g:
            g.write(f.read(n))


def main():
    out = sys.argv[1]
    write_bags(os.path.join(out, "ros_bag"))
    write_db3(os.path.join(out, "ros_bag"))
    write_messages(os.path.join(out, "ros_message"))
    write_raw(os.path.join(out, "prophesee"))
    write_ply(os.path.join(out, "ply"))
    if len(sys.argv) > 2:
        write_prefixes(out, sys.argv[2])


if __name__ == "__main__":
    main()
