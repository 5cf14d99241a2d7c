#!/usr/bin/env python3
"""Per-object mean radiosity of an OBJ + MTL scene with Mitsuba 3, as a check on `occ radiosity
--pathtrace`, which is our own ground truth.

Each object is loaded as its own mesh with face normals, a one-sided `diffuse` BSDF (Kd) and, if
Ke is set, an `area` emitter of radiance Ke. An `irradiancemeter` attached to the object measures
its mean irradiance H (cosine-weighted directions over its front, uniform points over its area),
and B = pi Ke + Kd H. Each object is measured in `--runs` independent renders (different seeds),
whose spread gives the standard error. Needs `pip install mitsuba` (3.x; variant scalar_rgb).

Usage: mitsuba_means.py SCENE.obj [--spp N] [--runs K] > out.json
"""
import argparse
import json
import math
import os
import sys
import tempfile
import time

import mitsuba as mi


def parse(obj_path):
    """Returns objects in file order: name -> (material, [(a, b, c) vertex triples])."""
    verts, objects, order = [], {}, []
    name, material, mtllib = "default", None, None
    with open(obj_path) as f:
        for line in f:
            w = line.split()
            if not w or w[0].startswith("#"):
                continue
            if w[0] == "v":
                verts.append(tuple(float(x) for x in w[1:4]))
            elif w[0] in ("o", "g"):
                name = w[1]
            elif w[0] == "usemtl":
                material = w[1]
            elif w[0] == "mtllib":
                mtllib = w[1]
            elif w[0] == "f":
                idx = [int(x.split("/")[0]) for x in w[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                if name not in objects:
                    objects[name] = (material, [])
                    order.append(name)
                for k in range(1, len(idx) - 1):
                    objects[name][1].append((verts[idx[0]], verts[idx[k]], verts[idx[k + 1]]))
    return [(n, objects[n]) for n in order], mtllib


def materials(mtl_path):
    out, cur = {}, None
    with open(mtl_path) as f:
        for line in f:
            w = line.split()
            if not w or w[0].startswith("#"):
                continue
            if w[0] == "newmtl":
                cur = out.setdefault(w[1], {"Kd": [0.5] * 3, "Ke": [0.0] * 3})
            elif w[0] in ("Kd", "Ke") and cur is not None:
                cur[w[0]] = [float(x) for x in w[1:4]]
    return out


def area(t):
    a, b, c = t
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    x = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    return 0.5 * math.sqrt(sum(y * y for y in x))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("--spp", type=int, default=1 << 16, help="samples per object per run")
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--max-depth", type=int, default=-1,
                    help="path length limit (1: direct light only; -1: none)")
    args = ap.parse_args()
    mi.set_variant("scalar_rgb")
    objects, mtllib = parse(args.scene)
    mats = materials(os.path.join(os.path.dirname(args.scene), mtllib))
    tmp = tempfile.mkdtemp()
    files = []
    for i, (name, (mat, tris)) in enumerate(objects):
        path = os.path.join(tmp, f"o{i}.obj")
        with open(path, "w") as f:
            for t in tris:
                for p in t:
                    f.write("v %r %r %r\n" % p)
            for k in range(len(tris)):
                f.write(f"f {3 * k + 1} {3 * k + 2} {3 * k + 3}\n")
        files.append(path)

    def scene_dict(measured):
        d = {"type": "scene", "integrator": {"type": "path", "max_depth": args.max_depth, "rr_depth": 5}}
        for i, (name, (mat, tris)) in enumerate(objects):
            m = mats[mat]
            shape = {
                "type": "obj",
                "filename": files[i],
                "face_normals": True,
                "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": m["Kd"]}},
            }
            if any(m["Ke"]):
                shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": m["Ke"]}}
            if i == measured:
                shape["sensor"] = {
                    "type": "irradiancemeter",
                    "film": {"type": "hdrfilm", "width": 1, "height": 1,
                             "pixel_format": "rgb", "rfilter": {"type": "box"}},
                }
            d[f"o{i}"] = shape
        return d

    start = time.time()
    result = []
    for i, (name, (mat, tris)) in enumerate(objects):
        scene = mi.load_dict(scene_dict(i))
        runs = []
        for r in range(args.runs):
            img = mi.render(scene, spp=args.spp, seed=1000 * i + r)
            px = list(mi.TensorXf(img).array)
            runs.append([float(px[c]) for c in range(3)])
        m = mats[mat]
        h = [sum(x[c] for x in runs) / len(runs) for c in range(3)]
        var = [sum((x[c] - h[c]) ** 2 for x in runs) / (len(runs) - 1) for c in range(3)]
        result.append({
            "name": name,
            "area": sum(area(t) for t in tris),
            "mean_b": [math.pi * m["Ke"][c] + m["Kd"][c] * h[c] for c in range(3)],
            "std_err": [m["Kd"][c] * math.sqrt(var[c] / len(runs)) for c in range(3)],
        })
        print(f"{name}: {result[-1]['mean_b']}", file=sys.stderr)
    json.dump({
        "tool": f"Mitsuba {mi.__version__} scalar_rgb, path integrator, irradiancemeter per object",
        "command": " ".join(["mitsuba_means.py"] + sys.argv[1:]),
        "samples_per_object": args.spp * args.runs,
        "seconds": time.time() - start,
        "objects": result,
    }, sys.stdout, indent=2)


if __name__ == "__main__":
    main()
