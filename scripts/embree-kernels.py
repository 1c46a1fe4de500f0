#!/usr/bin/env python3
"""Which Embree kernels this CPU gets, as `bench bvh` creates its scenes.

Loads the library `scripts/setup-embree.sh` extracted (`$EMBREE_DIR/embreex.libs`, default
`.embree/embreex.libs` of the repository), opens a device with `threads=1,verbose=3`, commits a
one-triangle scene in Embree's default mode and one in robust mode (`RTC_SCENE_FLAG_ROBUST`),
and prints the CPU's ISA line and, per mode, the tree Embree built and the `rtcIntersect1`
kernel it selected (for example `avx512::BVH8Triangle4Intersector1Moeller`). Embree picks its
SIMD path at run time, so this is the answer for the machine it runs on.

Usage: python3 scripts/embree-kernels.py
"""

import ctypes
import glob
import os
import subprocess
import sys

RTC_SCENE_FLAG_ROBUST = 4  # RTC_SCENE_FLAG_ROBUST = (1 << 2); 2 is RTC_SCENE_FLAG_COMPACT
RTC_GEOMETRY_TYPE_TRIANGLE = 0
RTC_BUFFER_TYPE_INDEX, RTC_BUFFER_TYPE_VERTEX = 0, 1
RTC_FORMAT_UINT3, RTC_FORMAT_FLOAT3 = 0x5003, 0x9003


def child(libs: str) -> None:
    """Commits the two scenes; Embree writes its verbose report to stdout."""
    for tbb in glob.glob(os.path.join(libs, "libtbb*.so*")):
        ctypes.CDLL(tbb, mode=ctypes.RTLD_GLOBAL)
    embree = ctypes.CDLL(glob.glob(os.path.join(libs, "libembree4*.so*"))[0])
    for name in ("rtcNewDevice", "rtcNewScene", "rtcNewGeometry", "rtcSetNewGeometryBuffer"):
        getattr(embree, name).restype = ctypes.c_void_p
    device = ctypes.c_void_p(embree.rtcNewDevice(b"threads=1,verbose=3"))
    if not device.value:
        sys.exit("rtcNewDevice failed")
    for mode, flags in (("default", 0), ("robust", RTC_SCENE_FLAG_ROBUST)):
        print(f"== mode {mode}", flush=True)
        scene = ctypes.c_void_p(embree.rtcNewScene(device))
        embree.rtcSetSceneFlags(scene, flags)
        geom = ctypes.c_void_p(embree.rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE))
        vertices = embree.rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, 3
        )
        indices = embree.rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, 1
        )
        if not (vertices and indices):
            sys.exit("rtcSetNewGeometryBuffer failed")
        v = ctypes.cast(vertices, ctypes.POINTER(ctypes.c_float))
        for i, x in enumerate((0, 0, 0, 1, 0, 0, 0, 1, 0)):
            v[i] = x
        ix = ctypes.cast(indices, ctypes.POINTER(ctypes.c_uint))
        for i in range(3):
            ix[i] = i
        embree.rtcCommitGeometry(geom)
        embree.rtcAttachGeometry(scene, geom)
        embree.rtcCommitScene(scene)
        sys.stdout.flush()


def main() -> None:
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    libs = os.path.join(os.environ.get("EMBREE_DIR", os.path.join(root, ".embree")), "embreex.libs")
    if not glob.glob(os.path.join(libs, "libembree4*.so*")):
        sys.exit(f"no Embree library in {libs}: run scripts/setup-embree.sh first")
    # Embree prints from C (its own stdout buffer): run in a child and read the whole report.
    out = subprocess.run(
        [sys.executable, __file__, "--child", libs], capture_output=True, text=True, check=True
    ).stdout
    mode, seen = None, set()
    for line in out.splitlines():
        s = " ".join(line.split())
        if s.startswith("ISA") and mode is None and "isa" not in seen:
            seen.add("isa")
            print(f"cpu {s}")
        elif s.startswith("== mode"):
            mode = s.split()[-1]
        elif mode and s.startswith(("building ", "intersector1 ")) and (mode, s) not in seen:
            seen.add((mode, s))
            print(f"{mode}: {s}")
    if mode is None:
        sys.exit("Embree printed no report")


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--child":
        child(sys.argv[2])
    else:
        main()
