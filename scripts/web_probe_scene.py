#!/usr/bin/env python3
"""docs/web.md's probe-lit scene, from nothing but data/: spot standing on a ground quad,
the quad and spot baked into a probe grid under the sky, exported with `shtool export-web
--probes` and captured in headless Chromium, spot seen from the front three-quarter (as
render's default view: 35 degrees round towards the model's left, 20 up).

Usage: web_probe_scene.py OUT_DIR [--shtool PATH] [--png PATH]

OUT_DIR receives spot_ground.obj, fit4.shtb, sky4.json, probes.shtb, the page folder page/
and the capture web-probes.png (or --png). Needs node and Debian's chromium on PATH, and
three@0.187.0 where export-web looks for it (docs/web.md): $SHTOOL_THREE_DIR or the build
tree's node_consumers/, which the tests' npm install fills.
"""
import argparse
import json
import math
import pathlib
import shutil
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
SPOT = ROOT / "data" / "spot.obj"
SKY = ROOT / "data" / "sky.hdr"
BROWSER = ROOT / "tests" / "consumer" / "node" / "export_web_browser.mjs"

# The probe grid's box in shtool's frame (z up): the quad's extent, from one cell below the
# ground to a little above spot's head, in LAYERS layers of probes. three samples the grid
# half a cell along a surface's normal and leaves a point unlit where that falls outside
# the box: the cell below the ground keeps the spheres' undersides inside it.
BOX_XY = 2.0
BOX_TOP = 1.3
LAYERS = 7


def run(*args):
    print("+", " ".join(str(a) for a in args), flush=True)
    subprocess.run([str(a) for a in args], check=True)


def spot_with_ground(out):
    """data/spot.obj and a BOX_XY-wide square quad at its feet, facing up (+y of the y-up
    file); returns the file's lowest y (shtool's lowest z)."""
    lines = SPOT.read_text().splitlines()
    positions = [tuple(map(float, l.split()[1:4])) for l in lines if l.startswith("v ")]
    floor = min(p[1] for p in positions)
    n = len(positions)
    quad = [(-BOX_XY, floor, -BOX_XY), (-BOX_XY, floor, BOX_XY), (BOX_XY, floor, BOX_XY), (BOX_XY, floor, -BOX_XY)]
    # Counter-clockwise seen from +y: the faces' normal is up.
    extra = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in quad]
    extra += [f"f {n + 1} {n + 2} {n + 3}", f"f {n + 1} {n + 3} {n + 4}"]
    # Vertices first, then faces: the quad's vertex lines go after spot's last vertex.
    last_v = max(i for i, l in enumerate(lines) if l.startswith("v "))
    out.write_text("\n".join(lines[: last_v + 1] + extra[:4] + lines[last_v + 1 :] + extra[4:]) + "\n")
    return floor


def front_camera(floor):
    """An eye at the front three-quarter of spot, far enough back to show the quad and the
    spheres: render's default direction (front +y for an OBJ, 35 degrees towards -x, 20 up),
    in shtool's frame."""
    positions = [tuple(map(float, l.split()[1:4])) for l in SPOT.read_text().splitlines() if l.startswith("v ")]
    # shtool = (x, -z, y) of the y-up file.
    xs = [p[0] for p in positions]
    ys = [-p[2] for p in positions]
    target = (0.5 * (min(xs) + max(xs)), 0.5 * (min(ys) + max(ys)), floor + 0.45)
    azimuth, elevation, distance = math.radians(35), math.radians(24), 4.9
    toward = (-math.cos(elevation) * math.sin(azimuth), math.cos(elevation) * math.cos(azimuth), math.sin(elevation))
    eye = tuple(t + distance * d for t, d in zip(target, toward))
    return eye, target


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", type=pathlib.Path)
    parser.add_argument("--shtool", type=pathlib.Path, default=ROOT / "build" / "shtool")
    parser.add_argument("--png", type=pathlib.Path, default=None)
    a = parser.parse_args()
    out = a.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    png = (a.png or out / "web-probes.png").resolve()
    if not png.parent.is_dir():
        sys.exit(f"web_probe_scene.py: --png {a.png}: folder {png.parent} does not exist")
    shtool = a.shtool.resolve()

    scene = out / "spot_ground.obj"
    floor = spot_with_ground(scene)
    fit, sky, probes, page = out / "fit4.shtb", out / "sky4.json", out / "probes.shtb", out / "page"
    run(shtool, "fit-zh", SPOT, "--order", 4, "--lobes", 3, "--rays", 256, "--out", fit)
    run(shtool, "project-env", SKY, "--order", 4, "--json", sky)
    bottom = floor - (BOX_TOP - floor) / (LAYERS - 1)
    bounds = f"--bounds={-BOX_XY},{-BOX_XY},{bottom:.4f},{BOX_XY},{BOX_XY},{BOX_TOP}"
    run(shtool, "bake-probes", scene, "--grid", f"16,16,{LAYERS}", bounds, "--env", sky, "--order", 3, "--samples", 512,
        "--bounces", 2, "--out", probes)
    eye, target = front_camera(floor)
    camera = ",".join(f"{v:.4f}" for v in (*eye, *target, 0, 0, 1))
    run(shtool, "export-web", SPOT, "--fit", fit, "--light", sky, "--probes", probes, f"--camera={camera}",
        "--width", 400, "--height", 300, "--out", page)

    with tempfile.TemporaryDirectory() as shots:
        print("+ node", BROWSER, "chromium", shots, page, flush=True)
        done = subprocess.run(["node", str(BROWSER), "chromium", shots, str(page)], check=True, capture_output=True,
                              text=True)
        result = json.loads(done.stdout.strip().splitlines()[-1])
        if "error" in result:
            sys.exit(f"web_probe_scene.py: the page did not draw: {result['error']}")
        shutil.copyfile(result["views"][0], png)
    print(f"{png}: {result['status'][0]}")


if __name__ == "__main__":
    main()
