#!/usr/bin/python3
"""Writes ROS 1 bags from an ECD text folder with Debian's python3-rosbag and message classes that
genpy generates from the message definitions: test input for eds's own bag reader (the two share no
code).

usage: write_bags.py SEQUENCE_DIR OUT_DIR MAX_EVENTS EVENTS_PER_MESSAGE [UNTIL_S [COMPRESSION]]
       write_bags.py --stereo SEQUENCE_DIR OUT_DIR UNTIL_S   (see write_stereo)
       write_bags.py --empty-packet OUT_DIR                  (see write_empty_packet)
       write_bags.py --odd-step OUT_DIR                      (see write_odd_step)
writes OUT_DIR/events_{none,bz2,lz4}.bag (dvs_msgs/EventArray on /dvs/events); with UNTIL_S also
OUT_DIR/recording.bag (lz4 unless COMPRESSION says otherwise): the events, frames (sensor_msgs/Image mono8 on /dvs/image_raw), the
calibration (sensor_msgs/CameraInfo on /dvs/camera_info) and the ground truth
(geometry_msgs/PoseStamped on /optitrack/davis) and IMU samples (sensor_msgs/Imu on /dvs/imu, see
write_imu) up to UNTIL_S seconds.
"""
import gzip
import struct
import sys

import genpy.dynamic
import rosbag
import rospy
from PIL import Image as PilImage

SEP = "=" * 80 + "\n"
HEADER = "MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n"
DEFINITIONS = {
    "dvs_msgs/EventArray": "std_msgs/Header header\nuint32 height\nuint32 width\nEvent[] events\n" + SEP + HEADER
    + SEP + "MSG: dvs_msgs/Event\nuint16 x\nuint16 y\ntime ts\nbool polarity\n",
    "sensor_msgs/Image": "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
    "uint8 is_bigendian\nuint32 step\nuint8[] data\n" + SEP + HEADER,
    "sensor_msgs/CameraInfo": "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n"
    "float64[] D\nfloat64[9] K\nfloat64[9] R\nfloat64[12] P\nuint32 binning_x\nuint32 binning_y\n"
    "RegionOfInterest roi\n" + SEP + HEADER + SEP
    + "MSG: sensor_msgs/RegionOfInterest\nuint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\n"
    "bool do_rectify\n",
    "sensor_msgs/Imu": "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
    "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
    "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n" + SEP + HEADER + SEP
    + "MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n" + SEP
    + "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n",
    "event_camera_msgs/EventPacket": "std_msgs/Header header\nuint32 height\nuint32 width\nuint64 seq\n"
    "uint64 time_base\nstring encoding\nbool is_bigendian\nuint8[] events\n" + SEP + HEADER,
    "geometry_msgs/PoseStamped": "std_msgs/Header header\ngeometry_msgs/Pose pose\n" + SEP + HEADER + SEP
    + "MSG: geometry_msgs/Pose\nPoint position\nQuaternion orientation\n" + SEP
    + "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n" + SEP
    + "MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n",
}


def classes():
    out = {}
    for name, text in DEFINITIONS.items():
        out.update(genpy.dynamic.generate_dynamic(name, text))
    return out


def stamp(t_text):
    """An ECD time ('12.345678901' s) as a rospy.Time, exactly (no float on the way)."""
    sec, _, frac = t_text.partition(".")
    return rospy.Time(int(sec), int((frac + "000000000")[:9]))


def read_events(seq_dir, max_events, until):
    Event = CLASSES["dvs_msgs/Event"]
    events = []
    with gzip.open(seq_dir + "/events.txt.gz", "rt") as f:
        for line in f:
            t, x, y, p = line.split()
            if len(events) >= max_events or (until is not None and float(t) > until):
                break
            events.append(Event(x=int(x), y=int(y), ts=stamp(t), polarity=p == "1"))
    return events


def write_events(bag, events, per_msg, width, height, topic="/dvs/events"):
    EventArray = CLASSES["dvs_msgs/EventArray"]
    for seq, i in enumerate(range(0, len(events), per_msg)):
        msg = EventArray(width=width, height=height, events=events[i:i + per_msg])
        msg.header.seq = seq
        msg.header.stamp = msg.events[-1].ts
        bag.write(topic, msg, t=msg.header.stamp)


def write_frames(bag, seq_dir, until, topic="/dvs/image_raw", invert=False):
    Image = CLASSES["sensor_msgs/Image"]
    size = None
    with open(seq_dir + "/images.txt") as f:
        for seq, line in enumerate(f):
            t, path = line.split()
            if float(t) > until:
                break
            img = PilImage.open(seq_dir + "/" + path).convert("L")
            if invert:
                img = img.point(lambda v: 255 - v)
            size = img.size
            msg = Image(height=img.size[1], width=img.size[0], encoding="mono8", is_bigendian=0,
                        step=img.size[0], data=img.tobytes())
            msg.header.seq, msg.header.stamp, msg.header.frame_id = seq, stamp(t), "dvs"
            bag.write(topic, msg, t=msg.header.stamp)
    return size


def write_camera_info(bag, seq_dir, size, topic="/dvs/camera_info", fx_offset=0.0):
    CameraInfo = CLASSES["sensor_msgs/CameraInfo"]
    v = [float(x) for x in open(seq_dir + "/calib.txt").read().split()]
    fx, fy, cx, cy, d = v[0] + fx_offset, v[1], v[2], v[3], (v[4:] + [0.0] * 5)[:5]
    msg = CameraInfo(height=size[1], width=size[0], distortion_model="plumb_bob", D=d,
                     K=[fx, 0, cx, 0, fy, cy, 0, 0, 1], R=[1, 0, 0, 0, 1, 0, 0, 0, 1],
                     P=[fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0])
    bag.write(topic, msg, t=rospy.Time(0, 1))


def write_ground_truth(bag, seq_dir, until):
    PoseStamped = CLASSES["geometry_msgs/PoseStamped"]
    with open(seq_dir + "/groundtruth.txt") as f:
        for line in f:
            t, px, py, pz, qx, qy, qz, qw = line.split()
            if float(t) > until:
                break
            msg = PoseStamped()
            msg.header.stamp = stamp(t)
            p, q = msg.pose.position, msg.pose.orientation
            p.x, p.y, p.z = float(px), float(py), float(pz)
            q.x, q.y, q.z, q.w = float(qx), float(qy), float(qz), float(qw)
            bag.write("/optitrack/davis", msg, t=msg.header.stamp)


def write_imu(bag, until):
    """200 Hz samples k = 0, 1, ...: angular velocity (0.01 k, -0.02 k, 0.5) rad/s, acceleration
    (0.1, 9.81, -0.2 k) m/s^2."""
    Imu = CLASSES["sensor_msgs/Imu"]
    k = 0
    while k * 0.005 <= until:
        msg = Imu()
        msg.header.stamp = rospy.Time(0, k * 5000000)
        msg.orientation.w = 1.0
        msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z = 0.01 * k, -0.02 * k, 0.5
        msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z = 0.1, 9.81, -0.2 * k
        bag.write("/dvs/imu", msg, t=msg.header.stamp)
        k += 1


def write_stereo(seq_dir, out_dir, until):
    """OUT_DIR/stereo.bag: two cameras as in the stereo DAVIS bags (/davis/left/..., /davis/right/...).
    The right one is told apart: every second event, inverted images, fx larger by 10."""
    events = read_events(seq_dir, 10**9, until)
    with rosbag.Bag(f"{out_dir}/stereo.bag", "w", compression="lz4") as bag:
        for side, invert, step, fx_offset in (("left", False, 1, 0.0), ("right", True, 2, 10.0)):
            size = write_frames(bag, seq_dir, until, f"/davis/{side}/image_raw", invert)
            write_camera_info(bag, seq_dir, size, f"/davis/{side}/camera_info", fx_offset)
            write_events(bag, events[::step], 500, size[0], size[1], f"/davis/{side}/events")


def write_empty_packet(out_dir):
    """OUT_DIR/empty_packet.bag: an evt3 EventPacket with no payload, then one with a single event
    (TIME_HIGH, TIME_LOW, Y 5, X 10 ON) at pixel (10, 5)."""
    Packet = CLASSES["event_camera_msgs/EventPacket"]
    words = [0x8000, 0x6010, 0x0005, 0x2000 | 0x800 | 10]
    with rosbag.Bag(f"{out_dir}/empty_packet.bag", "w") as bag:
        for k, payload in enumerate((b"", struct.pack("<4H", *words))):
            msg = Packet(height=720, width=1280, seq=k, time_base=0, encoding="evt3", is_bigendian=False,
                         events=payload)
            msg.header.stamp = rospy.Time(1, k * 1000)
            bag.write("/events", msg, t=msg.header.stamp)


def write_odd_step(out_dir):
    """OUT_DIR/odd_step.bag: one mono16 sensor_msgs/Image of 4x3 pixels, little-endian, whose rows are
    9 bytes apart (a padding byte 0xEE after each): pixel (x, y) holds 256 * (10 * y + x + 1) + 7."""
    Image = CLASSES["sensor_msgs/Image"]
    width, height, step = 4, 3, 9
    data = b"".join(struct.pack("<4H", *(256 * (10 * y + x + 1) + 7 for x in range(width))) + b"\xee"
                    for y in range(height))
    with rosbag.Bag(f"{out_dir}/odd_step.bag", "w") as bag:
        msg = Image(height=height, width=width, encoding="mono16", is_bigendian=0, step=step, data=data)
        msg.header.stamp = rospy.Time(1, 0)
        bag.write("/dvs/image_raw", msg, t=msg.header.stamp)


def write_libcaer(seq_dir, out_dir, until):
    """OUT_DIR/libcaer.bag: the events up to UNTIL s as event_camera_msgs/EventPacket, encoding "libcaer"
    (8-byte events: data = x << 17 | y << 2 | polarity << 1 | valid, int32 low 31 bits of the sensor's us),
    as libcaer_driver packs them. The sensor clock starts 0.1 s before its 31-bit counter wraps; each
    message's time_base is a ROS base time plus the sensor time's high bits, in ns."""
    Packet = CLASSES["event_camera_msgs/EventPacket"]
    ros_base_ns, offset_us, wrap = 1_700_000_000_000_000_000, 2**31 - 100_000, 2**31
    events = read_events(seq_dir, 10**9, until)
    with rosbag.Bag(f"{out_dir}/libcaer.bag", "w") as bag:
        for k, i in enumerate(range(0, len(events), 500)):
            part = events[i:i + 500]
            sensor_us = [e.ts.secs * 1_000_000 + e.ts.nsecs // 1000 + offset_us for e in part]
            high = sensor_us[0] - sensor_us[0] % wrap
            payload = b"".join(struct.pack("<Ii", e.x << 17 | e.y << 2 | int(e.polarity) << 1 | 1, us % wrap)
                               for e, us in zip(part, sensor_us))
            msg = Packet(height=180, width=240, seq=k, time_base=ros_base_ns + high * 1000, encoding="libcaer",
                         is_bigendian=False, events=payload)
            msg.header.stamp = part[-1].ts
            bag.write("/events", msg, t=msg.header.stamp)


def write_libcaer_bad(out_dir):
    """Damaged libcaer packets, one bag each: odd.bag (7 payload bytes), negative.bag (a negative
    timestamp), code.bag (a libcaer_cmp token of undefined code 7 after one good event)."""
    Packet = CLASSES["event_camera_msgs/EventPacket"]
    good = struct.pack("<4H", 0x0000, 0x1005, 0x2000 | 10, 0x3000 | 5)  # time 5 us, x 10, y 5 OFF
    cases = {"odd": ("libcaer", b"\x01" * 7), "negative": ("libcaer", struct.pack("<Ii", 1 << 17 | 1, -5)),
             "code": ("libcaer_cmp", good + struct.pack("<H", 0x7000))}
    for name, (encoding, payload) in cases.items():
        with rosbag.Bag(f"{out_dir}/{name}.bag", "w") as bag:
            msg = Packet(height=260, width=346, seq=0, time_base=10**18, encoding=encoding, is_bigendian=False,
                         events=payload)
            msg.header.stamp = rospy.Time(1, 0)
            bag.write("/events", msg, t=msg.header.stamp)


def main():
    if sys.argv[1] == "--libcaer-bad":
        write_libcaer_bad(sys.argv[2])
        return
    if sys.argv[1] == "--libcaer":
        write_libcaer(sys.argv[2], sys.argv[3], float(sys.argv[4]))
        return
    if sys.argv[1] == "--odd-step":
        write_odd_step(sys.argv[2])
        return
    if sys.argv[1] == "--empty-packet":
        write_empty_packet(sys.argv[2])
        return
    if sys.argv[1] == "--stereo":
        write_stereo(sys.argv[2], sys.argv[3], float(sys.argv[4]))
        return
    seq_dir, out_dir, max_events, per_msg = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    events = read_events(seq_dir, max_events, None)
    for compression in ("none", "bz2", "lz4"):
        with rosbag.Bag(f"{out_dir}/events_{compression}.bag", "w", compression=compression,
                        chunk_threshold=64 * 1024) as bag:
            write_events(bag, events, per_msg, 240, 180)
    if len(sys.argv) > 5:
        until = float(sys.argv[5])
        compression = sys.argv[6] if len(sys.argv) > 6 else "lz4"
        with rosbag.Bag(f"{out_dir}/recording.bag", "w", compression=compression) as bag:
            size = write_frames(bag, seq_dir, until)
            write_camera_info(bag, seq_dir, size)
            write_ground_truth(bag, seq_dir, until)
            write_imu(bag, until)
            write_events(bag, read_events(seq_dir, 10**9, until), per_msg, size[0], size[1])


CLASSES = classes()

if __name__ == "__main__":
    main()
