#!/usr/bin/python3
"""Writes calibration files in the layouts other datasets publish, with Python's json and Debian's
python3-yaml: a Basalt / TUM-VIE calibration JSON (Kannala-Brandt kb4) and a DSEC cam_to_cam.yaml.

usage: write_calibrations.py OUT_DIR
"""
import json
import sys

import yaml


def main():
    out = sys.argv[1]
    kb4 = {"camera_type": "kb4", "intrinsics": {"fx": 1049.5, "fy": 1049.4, "cx": 634.8, "cy": 361.2,
                                                "k1": 0.0033, "k2": -0.0056, "k3": 0.002, "k4": -0.0004}}
    pinhole = {"camera_type": "pinhole", "intrinsics": {"fx": 700.0, "fy": 701.0, "cx": 320.0, "cy": 240.0}}
    with open(out + "/basalt_calib.json", "w") as f:
        json.dump({"value0": {"T_imu_cam": [], "intrinsics": [kb4, pinhole], "resolution": [[1280, 720], [640, 480]],
                              "calib_accel_bias": [0.0] * 9}}, f, indent=4)
    with open(out + "/basalt_ds.json", "w") as f:
        json.dump({"value0": {"intrinsics": [{"camera_type": "ds", "intrinsics": {"fx": 1.0, "fy": 1.0, "cx": 1.0,
                                                                                   "cy": 1.0}}],
                              "resolution": [[64, 48]]}}, f)
    cam0 = {"camera_matrix": [553.47, 553.26, 346.65, 216.52], "camera_model": "pinhole",
            "distortion_coeffs": [-0.0931, 0.1968, 7.6e-05, -0.000377], "distortion_model": "radtan",
            "resolution": [640, 480]}
    rect = {"camera_matrix": [569.8, 569.8, 336.2, 222.5], "camera_model": "pinhole", "resolution": [640, 480]}
    with open(out + "/cam_to_cam.yaml", "w") as f:
        yaml.safe_dump({"intrinsics": {"cam0": cam0, "camRect0": rect},
                        "extrinsics": {"T_10": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}}, f)


if __name__ == "__main__":
    main()
