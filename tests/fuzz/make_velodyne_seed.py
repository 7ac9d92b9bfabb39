#!/usr/bin/env python3
# Writes the velodyne fuzz target's seed: every third LiDAR point around one parked car (track 17) of frame 0
# of a `beslam synth` dynamic_street render (the box tests/fuzz/velodyne.cpp refines), float32 x y z r.
#   build/bin/beslam synth --config dynamic_street --out /tmp/synth --set frames=1
#   tests/fuzz/make_velodyne_seed.py /tmp/synth/sequences/00/velodyne/000000.bin tests/fuzz/corpus/velodyne/parked-car.bin
import struct
import sys

scan = open(sys.argv[1], "rb").read()
near = []
for i in range(len(scan) // 16):
    x, y, z, r = struct.unpack_from("<4f", scan, 16 * i)
    # LiDAR to camera (synth's Tr_velo_to_cam): x_cam = -y, y_cam = -z - 0.08, z_cam = x - 0.27.
    if abs(-y - 2.726251) < 3 and abs(x - 0.27 - 17.150265) < 3.5 and -z - 0.08 < 1.6:
        near.append(scan[16 * i:16 * i + 16])
open(sys.argv[2], "wb").write(b"".join(near[::3]))
print(f"{len(near[::3])} points")
