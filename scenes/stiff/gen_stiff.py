# Writes the stiff scenes: a closed unit box whose six faces all emit E = 1 (Ke = 1/pi) with
# reflectance rho, so that B = E / (1 - rho) everywhere (the furnace test). Run from this folder.
RHOS = ["0.5", "0.9", "0.99", "0.999"]

def faces(s):
    # inward-facing quads (counter-clockwise seen from inside)
    return [
        ("floor",   [(0, 0, 0), (0, 0, s), (s, 0, s), (s, 0, 0)]),
        ("ceiling", [(0, s, 0), (s, s, 0), (s, s, s), (0, s, s)]),
        ("wall_x0", [(0, 0, 0), (0, s, 0), (0, s, s), (0, 0, s)]),
        ("wall_x1", [(s, 0, 0), (s, 0, s), (s, s, s), (s, s, 0)]),
        ("wall_z0", [(0, 0, 0), (s, 0, 0), (s, s, 0), (0, s, 0)]),
        ("wall_z1", [(0, 0, s), (0, s, s), (s, s, s), (s, 0, s)]),
    ]

mtl = ["# Materials of the stiff scenes: every face emits E = pi Ke = 1 and reflects rho."]
for rho in RHOS:
    mtl += ["", f"newmtl rho{rho}", f"Kd {rho} {rho} {rho}", "Ke 0.318309886 0.318309886 0.318309886"]
    b = 1 / (1 - float(rho))
    out = [f"# Stiff: closed unit box, every face emits E = 1 with reflectance {rho}: B = E / (1 - rho) = {b:g}.",
           "mtllib stiff.mtl"]
    vi = 1
    for name, quad in faces(1):
        out += [f"o {name}", f"usemtl rho{rho}"]
        out += ["v %g %g %g" % p for p in quad]
        out.append(f"f {vi} {vi + 1} {vi + 2} {vi + 3}")
        vi += 4
    open(f"box-{rho}.obj", "w").write("\n".join(out) + "\n")
open("stiff.mtl", "w").write("\n".join(mtl) + "\n")
