#!/usr/bin/python3
"""Writes an ECD text folder as a rosbag2 MCAP file with ROS 2 (CDR) messages, as `ros2 bag record`
would: dvs_msgs/msg/EventArray, sensor_msgs/msg/Image (mono8), sensor_msgs/msg/CameraInfo and
geometry_msgs/msg/PoseStamped, in chunks (uncompressed, or zstd by Debian's `zstd` program), with a
summary. Debian has no MCAP writer, so the framing follows the MCAP specification here; eds's reader is
also checked against a real MCAP file.

usage: write_mcap.py SEQ_DIR OUT.mcap UNTIL_S [zstd]"""
import struct
import subprocess
import sys

from PIL import Image

from esim_text import seconds_ns, text_events


class Cdr:
    """Little-endian CDR: each primitive aligned to its size, counted from after the 4-byte header."""

    def __init__(self):
        self.b = bytearray()

    def align(self, n):
        self.b += b"\0" * (-len(self.b) % n)

    def put(self, fmt, *values):
        self.align(struct.calcsize("<" + fmt.lstrip("0123456789")[0]))
        self.b += struct.pack("<" + fmt, *values)
        return self

    def string(self, s):
        data = s.encode() + b"\0"
        self.put("I", len(data))
        self.b += data
        return self

    def header(self, sec, nsec, frame="cam"):
        return self.put("iI", sec, nsec).string(frame)

    def bytes(self):
        return b"\0\x01\0\0" + bytes(self.b)


def record(op, body):
    return struct.pack("<BQ", op, len(body)) + body


def string(s):
    return struct.pack("<I", len(s)) + s.encode()


class Writer:
    def __init__(self, path, compression):
        self.f = open(path, "wb")
        self.f.write(b"\x89MCAP0\r\n")
        self.f.write(record(0x01, string("ros2") + string("eds write_mcap.py")))
        self.compression, self.chunk, self.schemas, self.channels, self.counts = compression, [], {}, {}, {}
        self.times = []

    def message(self, topic, type_name, t_ns, data):
        if topic not in self.channels:
            sid = len(self.schemas) + 1
            self.schemas[type_name] = record(0x03, struct.pack("<H", sid) + string(type_name) + string("ros2msg")
                                             + struct.pack("<I", 0))
            cid = len(self.channels)
            self.channels[topic] = (cid, record(0x04, struct.pack("<HH", cid, sid) + string(topic) + string("cdr")
                                                + struct.pack("<I", 0)))
            self.chunk += [self.schemas[type_name], self.channels[topic][1]]
        cid = self.channels[topic][0]
        self.counts[cid] = self.counts.get(cid, 0) + 1
        self.chunk.append(record(0x05, struct.pack("<HIQQ", cid, self.counts[cid], t_ns, t_ns) + data))
        self.times.append(t_ns)
        if sum(len(r) for r in self.chunk) > 1 << 20:
            self.flush()

    def flush(self):
        if not self.chunk:
            return
        raw = b"".join(self.chunk)
        data = raw if self.compression == "" else subprocess.run(["zstd", "-q", "-c", f"--stream-size={len(raw)}"],
                                                                 input=raw, stdout=subprocess.PIPE, check=True).stdout
        body = struct.pack("<QQQI", min(self.times), max(self.times), len(raw), 0) + string(self.compression)
        self.f.write(record(0x06, body + struct.pack("<Q", len(data)) + data))
        self.chunk, self.times = [], []

    def close(self):
        self.flush()
        self.f.write(record(0x0F, struct.pack("<I", 0)))
        start = self.f.tell()
        summary = b"".join(self.schemas.values()) + b"".join(c[1] for c in self.channels.values())
        counts = b"".join(struct.pack("<HQ", cid, n) for cid, n in self.counts.items())
        stats = struct.pack("<QHIIIIQQ", sum(self.counts.values()), len(self.schemas), len(self.channels), 0, 0, 0,
                            0, 0) + struct.pack("<I", len(counts)) + counts
        self.f.write(summary + record(0x0B, stats))
        self.f.write(record(0x02, struct.pack("<QQI", start, 0, 0)))
        self.f.write(b"\x89MCAP0\r\n")
        self.f.close()


def main():
    seq_dir, out, until = sys.argv[1], sys.argv[2], float(sys.argv[3])
    w = Writer(out, sys.argv[4] if len(sys.argv) > 4 else "")
    items = []  # (t_ns, topic, type, data), written in time order
    with open(seq_dir + "/images.txt") as f:
        for line in f:
            t, path = line.split()
            if float(t) > until:
                break
            img = Image.open(seq_dir + "/" + path).convert("L")
            s, ns = seconds_ns(t)
            c = Cdr().header(s, ns).put("II", img.height, img.width).string("mono8").put("B", 0).put("I", img.width)
            c.put("I", img.width * img.height)
            c.b += img.tobytes()
            items.append((s * 10**9 + ns, "/dvs/image_raw", "sensor_msgs/msg/Image", c.bytes()))
            size = img.size
    with open(seq_dir + "/calib.txt") as f:
        fx, fy, cx, cy = (float(v) for v in f.read().split()[:4])
    c = Cdr().header(0, 0).put("II", size[1], size[0]).string("plumb_bob").put("I", 5).put("5d", *([0.0] * 5))
    c.put("9d", fx, 0, cx, 0, fy, cy, 0, 0, 1).put("9d", 1, 0, 0, 0, 1, 0, 0, 0, 1)
    c.put("12d", fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0).put("II", 0, 0).put("IIII", 0, 0, 0, 0).put("B", 0)
    items.append((0, "/dvs/camera_info", "sensor_msgs/msg/CameraInfo", c.bytes()))
    with open(seq_dir + "/groundtruth.txt") as f:
        for line in f:
            v = line.split()
            if not v or v[0].startswith("#") or float(v[0]) > until:
                continue
            s, ns = seconds_ns(v[0])
            c = Cdr().header(s, ns, "world").put("7d", *(float(x) for x in v[1:8]))
            items.append((s * 10**9 + ns, "/optitrack/pose", "geometry_msgs/msg/PoseStamped", c.bytes()))
    events = [(seconds_ns(t), x, y, p == 1) for t, x, y, p in text_events(seq_dir, until)]
    for i in range(0, len(events), 2500):
        part = events[i:i + 2500]
        (s, ns) = part[-1][0]
        c = Cdr().header(s, ns).put("II", size[1], size[0]).put("I", len(part))
        for (es, ens), x, y, p in part:
            c.put("HH", x, y).put("iI", es, ens).put("B", int(p))
        items.append((s * 10**9 + ns, "/dvs/events", "dvs_msgs/msg/EventArray", c.bytes()))
    for t, topic, type_name, data in sorted(items, key=lambda it: it[0]):
        w.message(topic, type_name, t, data)
    w.close()


if __name__ == "__main__":
    main()
