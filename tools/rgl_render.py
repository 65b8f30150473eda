#!/usr/bin/env python3
"""Renders a sphere with an RGL tensor file (lsqt-cl export --rgl) in Mitsuba 3, in
lssview's scene, so that the two pictures of one LSS can be set side by side.

    PY tools/rgl_render.py IN.bsdf OUT.png [--dim 256] [--spp 256] [--light X,Y,Z,E ...]

PY: a Python with `mitsuba` and `numpy` (pip install mitsuba numpy; test_rgl makes such a
venv in build/client-venv). The scene is lssview's (tools/lssview/lssview.cpp): a unit
sphere seen by an orthographic camera down -z whose image is 1/0.45 sphere radii wide,
the same directional lights (towards (X, Y, Z) in camera space, +x right, +y up, +z to the
camera, irradiance E; default lssview's three), direct light only, and the same tone
map, 1 - exp(-v), sRGB encoded. The BSDF is Mitsuba's `measured` plugin (variant
scalar_rgb) reading IN.bsdf: its own interpolation of the tensor and its own sampling."""
import argparse
import math
import sys

import numpy as np

LIGHTS = [(-1, 1, 1.2, 2.5), (1, 0.2, 0.6, 0.8), (0, 1, -0.3, 1.2)]  # lssview's defaults
SPHERE_FRAC = 0.45  # sphere radius / image width, as lssview


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("bsdf")
    ap.add_argument("out")
    ap.add_argument("--dim", type=int, default=256)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--light", action="append", help="X,Y,Z,E (repeat; replaces the defaults)")
    a = ap.parse_args(argv)
    lights = [tuple(float(x) for x in l.split(",")) for l in a.light] if a.light else LIGHTS
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    half = 0.5 / SPHERE_FRAC  # the image's half width in sphere radii
    scene = {
        "type": "scene",
        "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0},
        # Mitsuba's camera frame has +x to the left: mirrored in x, the image has +x right.
        "sensor": {"type": "orthographic",
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0])
                   @ mi.ScalarTransform4f().scale([half, half, 1]),
                   "film": {"type": "hdrfilm", "width": a.dim, "height": a.dim, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": a.spp}},
        "sphere": {"type": "sphere", "bsdf": {"type": "measured", "filename": a.bsdf}},
    }
    for k, (x, y, z, e) in enumerate(lights):
        n = math.sqrt(x * x + y * y + z * z)
        # lssview's light is the direction towards it; Mitsuba's, the direction light travels.
        scene["light%d" % k] = {"type": "directional", "direction": [-x / n, -y / n, -z / n],
                                "irradiance": {"type": "rgb", "value": e}}
    img = np.array(mi.render(mi.load_dict(scene)))[:, :, 0]
    v = 1.0 - np.exp(-np.maximum(img, 0.0))
    s = np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1 / 2.4) - 0.055)
    g = np.clip(np.round(s * 255), 0, 255).astype(np.uint8)
    mi.util.write_bitmap(a.out, np.repeat(g[:, :, None], 3, axis=2), write_async=False)
    print("rgl_render: %s (%d x %d, %d samples a pixel; Mitsuba %s, measured BSDF from %s)"
          % (a.out, a.dim, a.dim, a.spp, mi.__version__, a.bsdf))


if __name__ == "__main__":
    main(sys.argv[1:])
