#!/usr/bin/python3
"""Writes AEDAT 4.0 files with Debian's python3-flatbuffers (the tables built by its Builder) and the lz4 /
zstd command-line tools: test input for eds's own AEDAT reader and FlatBuffer view (they share no code).

usage: write_aedat4.py SEQUENCE_DIR OUT.aedat4 COMPRESSION [UNTIL_S]
    events (EVTS, 5000 per packet) and frames (FRME, gray) of an ECD folder up to UNTIL_S seconds, and
    IMU samples at 200 Hz (IMUS: k = 0, 1, ... with gyro (k, -2k, 50) deg/s, acc (0.01, 1, -0.02 k) g)
    and a trigger packet (TRIG); COMPRESSION is none, lz4 or zstd.
usage: write_aedat4.py --header-only OUT.aedat4 XML
    an IOHeader with the given XML and no packets.

Layouts (iniVation's dv-processing schemas): IOHeader {compression: int32 (0 none, 1 lz4, 3 zstd),
dataTablePosition: int64, infoNode: string}; packets are size-prefixed FlatBuffers with a file identifier:
EventPacket {elements: [Event]} with struct Event {timestamp: int64 us; x, y: int16; polarity: bool};
Frame {timestamp 0, timestampStartOfExposure 3, timestampEndOfExposure 4 (int64 us), format 5 (int8, 0
gray), sizeX 6, sizeY 7 (int16), pixels 10 ([ubyte])}: frame k > 0 exposed for 1 + (k mod 3) ms around
its time stamp, frame 0 without exposure fields;
IMUPacket {elements: [IMU]} with IMU {timestamp 0, temperature 1, accelerometerX..Z 2-4 (g),
gyroscopeX..Z 5-7 (deg/s)}; TriggerPacket {elements: [Trigger]} with Trigger {timestamp 0, type 1}.
"""
import gzip
import struct
import subprocess
import sys

import flatbuffers
from PIL import Image

MAGIC = b"#!AER-DAT4.0\r\n"
COMPRESSION = {"none": 0, "lz4": 1, "zstd": 3}


def stream_xml(width, height):
    node = ('<node name="{i}" path="/mainloop/Recorder/outInfo/{i}/"><attr key="compression" type="string">NONE'
            '</attr><attr key="originalModuleName" type="string">capture</attr><attr key="originalOutputName" '
            'type="string">{name}</attr><attr key="typeDescription" type="string">{name}</attr><attr '
            'key="typeIdentifier" type="string">{type}</attr><node name="info" path="/mainloop/Recorder/outInfo/{i}/info/">'
            '<attr key="sizeX" type="int">{w}</attr><attr key="sizeY" type="int">{h}</attr><attr key="source" '
            'type="string">DAVIS346_test</attr></node></node>')
    parts = [node.format(i=i, name=n, type=t, w=width, h=height)
             for i, (n, t) in enumerate((("events", "EVTS"), ("frames", "FRME"), ("imu", "IMUS"), ("triggers", "TRIG")))]
    return '<dv version="2.0"><node name="outInfo" path="/mainloop/Recorder/outInfo/">' + "".join(parts) + "</node></dv>"


def io_header(compression, xml):
    b = flatbuffers.Builder(1024)
    info = b.CreateString(xml)
    b.StartObject(3)
    b.PrependInt32Slot(0, compression, 0)
    b.PrependInt64Slot(1, -1, 0)
    b.PrependUOffsetTRelativeSlot(2, info, 0)
    b.Finish(b.EndObject())
    return bytes(b.Output())


def events_packet(events):
    b = flatbuffers.Builder(16 * len(events) + 64)
    b.StartVector(16, len(events), 8)
    for t_us, x, y, on in reversed(events):
        b.Prep(8, 16)
        b.Pad(3)
        b.PrependBool(on)
        b.PrependInt16(y)
        b.PrependInt16(x)
        b.PrependInt64(t_us)
    vec = b.EndVector()
    b.StartObject(1)
    b.PrependUOffsetTRelativeSlot(0, vec, 0)
    b.FinishSizePrefixed(b.EndObject(), b"EVTS")
    return bytes(b.Output())


def frame_packet(t_us, img, exposure_us):
    b = flatbuffers.Builder(img.size[0] * img.size[1] + 256)
    pixels = b.CreateByteVector(img.tobytes())
    b.StartObject(12)
    b.PrependInt64Slot(0, t_us, 0)
    if exposure_us > 0:
        b.PrependInt64Slot(3, t_us - exposure_us // 2, 0)
        b.PrependInt64Slot(4, t_us - exposure_us // 2 + exposure_us, 0)
    b.PrependInt8Slot(5, 0, 0)
    b.PrependInt16Slot(6, img.size[0], 0)
    b.PrependInt16Slot(7, img.size[1], 0)
    b.PrependUOffsetTRelativeSlot(10, pixels, 0)
    b.FinishSizePrefixed(b.EndObject(), b"FRME")
    return bytes(b.Output())


def tables_packet(identifier, rows):
    """A packet whose field 0 is a vector of tables; each row is a list of (slot, kind, value)."""
    b = flatbuffers.Builder(1024)
    offsets = []
    for row in rows:
        b.StartObject(11)
        for slot, kind, value in row:
            {"i64": b.PrependInt64Slot, "f32": b.PrependFloat32Slot, "i8": b.PrependInt8Slot}[kind](slot, value, 0)
        offsets.append(b.EndObject())
    b.StartVector(4, len(offsets), 4)
    for o in reversed(offsets):
        b.PrependUOffsetTRelative(o)
    vec = b.EndVector()
    b.StartObject(1)
    b.PrependUOffsetTRelativeSlot(0, vec, 0)
    b.FinishSizePrefixed(b.EndObject(), identifier)
    return bytes(b.Output())


def compress(data, compression):
    if compression == "none":
        return data
    cmd = ["lz4", "-c", "-q"] if compression == "lz4" else ["zstd", "-c", "-q"]
    return subprocess.run(cmd, input=data, stdout=subprocess.PIPE, check=True).stdout


def us(t_text):
    sec, _, frac = t_text.partition(".")
    return int(sec) * 1000000 + int((frac + "000000000")[:9]) // 1000


def write_recording(seq_dir, out, compression, until):
    frames = []
    with open(seq_dir + "/images.txt") as f:
        for line in f:
            t, path = line.split()
            if until is not None and float(t) > until:
                break
            frames.append((us(t), Image.open(seq_dir + "/" + path).convert("L")))
    width, height = frames[0][1].size
    opener = gzip.open if not __import__("os").path.exists(seq_dir + "/events.txt") else open
    name = seq_dir + ("/events.txt" if opener is open else "/events.txt.gz")
    events = []
    with opener(name, "rt") as f:
        for line in f:
            t, x, y, p = line.split()
            if until is not None and float(t) > until:
                break
            events.append((us(t), int(x), int(y), p == "1"))
    packets = []  # (time, stream, bytes), in time order as DV writes them
    for i in range(0, len(events), 5000):
        packets.append((events[i + min(4999, len(events) - 1 - i)][0], 0, events_packet(events[i:i + 5000])))
    for k, (t, img) in enumerate(frames):
        packets.append((t, 1, frame_packet(t, img, 0 if k == 0 else 1000 * (1 + k % 3))))
    imu = [[(0, "i64", 5000 * k), (1, "f32", 30.0), (2, "f32", 0.01), (3, "f32", 1.0), (4, "f32", -0.02 * k),
            (5, "f32", float(k)), (6, "f32", -2.0 * k), (7, "f32", 50.0)] for k in range(int((until or 1.0) * 200) + 1)]
    packets.append((imu[-1][0][2], 2, tables_packet(b"IMUS", imu)))
    packets.append((0, 3, tables_packet(b"TRIG", [[(0, "i64", 1000), (1, "i8", 2)], [(0, "i64", 2000), (1, "i8", 3)]])))
    packets.sort(key=lambda p: (p[0], p[1]))
    write_file(out, COMPRESSION[compression], stream_xml(width, height),
               [(s, compress(data, compression)) for _, s, data in packets])


def write_file(out, compression, xml, packets):
    header = io_header(compression, xml)
    with open(out, "wb") as f:
        f.write(MAGIC + struct.pack("<i", len(header)) + header)
        for stream, data in packets:
            f.write(struct.pack("<ii", stream, len(data)) + data)


def main():
    if sys.argv[1] == "--header-only":
        write_file(sys.argv[2], 0, sys.argv[3], [])
        return
    until = float(sys.argv[4]) if len(sys.argv) > 4 else None
    write_recording(sys.argv[1], sys.argv[2], sys.argv[3], until)


if __name__ == "__main__":
    main()
