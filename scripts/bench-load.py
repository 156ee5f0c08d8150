#!/usr/bin/env python3
"""Scene load time and peak memory: ember against Mitsuba 3 on the same generated files
(issue 51, docs/reliability.md "Large scenes").

    scripts/bench-load.py [--sizes 1000,10000,100000,400000] [--ply-triangles 2000000]
                          [--out /tmp/ember-bench-load] [--ember target/release/ember]
                          [--before OLD_EMBER] [--before-max 10000] [--mitsuba-python python3]
                          [--repeat 1]

Writes, under --out (never in the repository):
- spheres-N.xml: N small spheres in a grid in front of a camera, a constant emitter and
  a 16 x 12 film (one `<shape>` element per sphere, the case that was quadratic);
- mesh-T.ply (binary little-endian, a grid of T triangles) and mesh-T.xml using it.

Measures, for each file:
- ember: `ember render FILE --spp 1 --no-plan` (the file's 16 x 12 film; no plan pilot):
  the whole process, i.e. reading, parsing, instantiating, the BVH, one sample per pixel
  and writing the image, with /usr/bin/time's wall time and peak RSS. Loads over a second also print their own
  load time on stderr ("loading FILE: done, N shapes (X s)": parsing and instantiating,
  without the BVH), shown as `load_s`.
- --before: the same with an older ember binary, for files of at most --before-max
  shapes (the quadratic reader took 22 s for 10 000 spheres).
- Mitsuba 3 (`scalar_rgb`): `mi.load_file(FILE)` timed inside Python (its scene load:
  parsing, shape instantiation, its acceleration structure) and the whole process's
  wall time and peak RSS (Python and Mitsuba's import included: ~0.4 s, see the `import`
  row).

Prints a markdown table on stdout.
"""
import argparse
import math
import os
import re
import struct
import subprocess
import sys

SENSOR = """<sensor type="perspective"><float name="fov" value="45"/>
  <transform name="to_world"><lookat origin="0 0 -10" target="0 0 0" up="0 1 0"/></transform>
  <sampler type="independent"><integer name="sample_count" value="1"/></sampler>
  <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/><rfilter type="box"/></film></sensor>
<emitter type="constant"/>
"""


def write_spheres(path, n):
    k = max(1, math.ceil(math.sqrt(n)))
    r = 2.0 / k
    with open(path, "w") as f:
        f.write('<scene version="3.0.0">\n' + SENSOR)
        for i in range(n):
            x = (i % k) / k * 8 - 4
            y = (i // k) / k * 8 - 4
            f.write(f'<shape type="sphere"><point name="center" x="{x:.6f}" y="{y:.6f}" z="0"/><float name="radius" value="{r:.6f}"/></shape>\n')
        f.write("</scene>\n")


def write_ply_scene(xml_path, ply_path, triangles):
    # A k x k grid of quads (two triangles each) in [-4, 4]^2 at z = 0.
    k = max(1, int(math.sqrt(triangles / 2)))
    verts = (k + 1) * (k + 1)
    with open(ply_path, "wb") as f:
        f.write(
            (
                f"ply\nformat binary_little_endian 1.0\nelement vertex {verts}\nproperty float x\nproperty float y\nproperty float z\n"
                f"element face {2 * k * k}\nproperty list uchar int vertex_indices\nend_header\n"
            ).encode()
        )
        row = bytearray()
        for j in range(k + 1):
            row.clear()
            for i in range(k + 1):
                row += struct.pack("<fff", i / k * 8 - 4, j / k * 8 - 4, 0.0)
            f.write(row)
        for j in range(k):
            row.clear()
            for i in range(k):
                a = j * (k + 1) + i
                b, c, d = a + 1, a + k + 2, a + k + 1
                row += struct.pack("<Biii", 3, a, b, c) + struct.pack("<Biii", 3, a, c, d)
            f.write(row)
    with open(xml_path, "w") as f:
        f.write('<scene version="3.0.0">\n' + SENSOR)
        f.write(f'<shape type="ply"><string name="filename" value="{os.path.basename(ply_path)}"/></shape>\n</scene>\n')
    return 2 * k * k


def timed(cmd):
    """(wall seconds, peak RSS MiB, stdout, stderr) of `cmd` under /usr/bin/time."""
    full = ["/usr/bin/time", "-f", "TIME %e %M"] + cmd
    p = subprocess.run(full, capture_output=True, text=True)
    m = re.findall(r"TIME ([0-9.]+) ([0-9]+)", p.stderr)
    if p.returncode != 0 or not m:
        sys.stderr.write(f"failed: {' '.join(cmd)}\n{p.stdout[-2000:]}\n{p.stderr[-2000:]}\n")
        return None
    wall, kb = m[-1]
    return float(wall), int(kb) / 1024, p.stdout, p.stderr


def ember(binary, scene, out):
    r = timed([binary, "render", scene, "--spp", "1", "--no-plan", "-o", os.path.join(out, "ember.exr")])
    if r is None:
        return None
    wall, mib, _, err = r
    load = re.findall(r"loading .*: done, \d+ shapes? \(([0-9.]+) s\)", err)
    return wall, mib, float(load[-1]) if load else None


MITSUBA = """
import sys, time
import mitsuba as mi
mi.set_variant("scalar_rgb")
if sys.argv[1] != "-":
    t = time.perf_counter()
    mi.load_file(sys.argv[1])
    print("LOAD", time.perf_counter() - t)
"""


def mitsuba(python, scene):
    r = timed([python, "-c", MITSUBA, scene])
    if r is None:
        return None
    wall, mib, out, _ = r
    load = re.findall(r"LOAD ([0-9.eE+-]+)", out)
    return wall, mib, float(load[-1]) if load else None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="1000,10000,100000,400000")
    ap.add_argument("--ply-triangles", type=int, default=2_000_000)
    ap.add_argument("--out", default="/tmp/ember-bench-load")
    ap.add_argument("--ember", default="target/release/ember")
    ap.add_argument("--before", default=None, help="an older ember binary, run on files of at most --before-max shapes")
    ap.add_argument("--before-max", type=int, default=10_000)
    ap.add_argument("--mitsuba-python", default="python3", help="a Python with `pip install mitsuba`; 'none' to skip Mitsuba")
    ap.add_argument("--repeat", type=int, default=1, help="runs per measurement; the fastest is kept")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    cases = []
    for n in [int(s) for s in args.sizes.split(",") if s]:
        path = os.path.join(args.out, f"spheres-{n}.xml")
        if not os.path.exists(path):
            write_spheres(path, n)
        cases.append((f"{n} spheres", path, n))
    if args.ply_triangles > 0:
        xml = os.path.join(args.out, f"mesh-{args.ply_triangles}.xml")
        ply = os.path.join(args.out, f"mesh-{args.ply_triangles}.ply")
        tris = write_ply_scene(xml, ply, args.ply_triangles)
        cases.append((f"PLY, {tris} triangles ({os.path.getsize(ply) / 2**20:.0f} MiB)", xml, 1))

    def best(f, *a):
        runs = [r for r in (f(*a) for _ in range(args.repeat)) if r is not None]
        return min(runs, key=lambda r: r[0]) if runs else None

    fmt = lambda v, p: "–" if v is None else f"{v:.{p}f}"
    print("| scene | ember s | ember load_s | ember MiB | before s | Mitsuba load_file s | Mitsuba s | Mitsuba MiB |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    if args.mitsuba_python != "none":
        m = best(mitsuba, args.mitsuba_python, "-")
        print(f"| import only (Python + Mitsuba) | | | | | | {fmt(m and m[0], 2)} | {fmt(m and m[1], 0)} |")
    for name, path, shapes in cases:
        e = best(ember, args.ember, path, args.out)
        b = best(ember, args.before, path, args.out) if args.before and shapes <= args.before_max else None
        m = best(mitsuba, args.mitsuba_python, path) if args.mitsuba_python != "none" else None
        print(
            f"| {name} | {fmt(e and e[0], 2)} | {fmt(e and e[2], 2)} | {fmt(e and e[1], 0)} | {fmt(b and b[0], 2)} "
            f"| {fmt(m and m[2], 2)} | {fmt(m and m[0], 2)} | {fmt(m and m[1], 0)} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
