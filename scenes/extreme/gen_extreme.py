# Writes the extreme test scenes (see README.md beside this script). Run from this folder.
# Most are the closed test box of scenes/gen_tests.py (unit box, reflectance 0.7, a 0.3 x 0.3
# light just under the ceiling) with one thing made extreme.

def box_faces(lo, s):
    x0, y0, z0 = lo
    x1, y1, z1 = x0 + s, y0 + s, z0 + s
    return [
        ("floor",   [(x0, y0, z0), (x0, y0, z1), (x1, y0, z1), (x1, y0, z0)]),
        ("ceiling", [(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)]),
        ("wall_x0", [(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)]),
        ("wall_x1", [(x1, y0, z0), (x1, y0, z1), (x1, y1, z1), (x1, y1, z0)]),
        ("wall_z0", [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)]),
        ("wall_z1", [(x0, y0, z1), (x0, y1, z1), (x1, y1, z1), (x1, y0, z1)]),
    ]

class Obj:
    def __init__(self, header):
        self.lines = [f"# {header}", "mtllib extreme.mtl"]
        self.n = 0
    def obj(self, name, mtl):
        self.lines += [f"o {name}", f"usemtl {mtl}"]
    def poly(self, pts):
        for p in pts:
            self.lines.append("v %.12g %.12g %.12g" % tuple(p))
        self.lines.append("f " + " ".join(str(self.n + 1 + i) for i in range(len(pts))))
        self.n += len(pts)
    def raw(self, line):
        self.lines.append(line)
    def write(self, path):
        open(path, "w").write("\n".join(self.lines) + "\n")

def light(o, lo, s, name="light", mtl="light", a=0.35, b=0.65):
    x0, y0, z0 = lo
    h = y0 + s * (1 - 1e-3)
    o.obj(name, mtl)
    o.poly([(x0 + a * s, h, z0 + a * s), (x0 + b * s, h, z0 + a * s),
            (x0 + b * s, h, z0 + b * s), (x0 + a * s, h, z0 + b * s)])

def test_box(header, lo=(0, 0, 0), s=1.0, skip=()):
    o = Obj(header)
    for name, q in box_faces(lo, s):
        if name not in skip:
            o.obj(name, "white")
            o.poly(q)
    return o

# Scale and offset: a power-of-two box (2^17) moved 2^20 (about 1e6) from the origin; and a box of
# 1e-3 units at 1e6, which single precision cannot place (refused, naming the line).
S, OFF = 131072.0, 1048576.0
o = test_box("Extreme: the closed test box at 2^17 units, moved 2^20 from the origin.", (OFF, OFF, OFF), S)
light(o, (OFF, OFF, OFF), S)
o.write("far-huge-box.obj")
o = test_box("Extreme: a box of 1e-3 units 1e6 from the origin: below single-precision resolution there, refused.", (1e6, 1e6, 1e6), 1e-3)
light(o, (1e6, 1e6, 1e6), 1e-3)
o.write("far-tiny-box.obj")

# Slivers of aspect 1e4: the floor is a 1 x (1 - 1e-4) quad and a 1 x 1e-4 strip beside it.
o = test_box("Extreme: the floor has a strip 1e-4 wide and 1 long (aspect 1e4).", skip=("floor",))
o.obj("floor", "white")
w = 1e-4
o.poly([(0, 0, 0), (0, 0, 1 - w), (1, 0, 1 - w), (1, 0, 0)])
o.obj("floor_sliver", "white")
o.poly([(0, 0, 1 - w), (0, 0, 1), (1, 0, 1), (1, 0, 1 - w)])
light(o, (0, 0, 0), 1.0)
o.write("sliver-1e4.obj")

# Zero-area and duplicate triangles: the test box with a repeated-vertex face, a collinear face
# and every ceiling triangle given twice.
o = test_box("Extreme: the test box plus zero-area faces (a repeated vertex, three collinear points) and a duplicated ceiling.")
o.obj("floor", "white")
o.poly([(0.2, 0, 0.2), (0.2, 0, 0.2), (0.5, 0, 0.7)])
o.poly([(0.1, 0, 0.1), (0.3, 0, 0.3), (0.6, 0, 0.6)])
o.obj("ceiling", "white")
o.poly([(0, 1, 0), (1, 1, 0), (1, 1, 1), (0, 1, 1)])
light(o, (0, 0, 0), 1.0)
o.write("degenerate.obj")

# Coincident coplanar faces: a rug exactly in the plane of the floor, over part of it.
o = test_box("Extreme: a dark rug coincident with (in the plane of) the floor.")
o.obj("rug", "dark")
o.poly([(0.25, 0, 0.25), (0.25, 0, 0.75), (0.75, 0, 0.75), (0.75, 0, 0.25)])
light(o, (0, 0, 0), 1.0)
o.write("coplanar.obj")

# Surfaces 1e-6 of the scene size apart: a dark panel 1e-6 above the floor, facing up.
o = test_box("Extreme: a dark panel 1e-6 above the floor (a gap of 1e-6 of the scene size).")
o.obj("panel", "dark")
g = 1e-6
o.poly([(0.25, g, 0.25), (0.25, g, 0.75), (0.75, g, 0.75), (0.75, g, 0.25)])
light(o, (0, 0, 0), 1.0)
o.write("gap-1e-6.obj")

# Receivers at the corners and edges of a source: the light fills a corner of the ceiling, its
# edges on two walls and its corner where they meet the ceiling.
o = test_box("Extreme: a light in the plane of the ceiling filling its corner: walls meet its edges.", skip=("ceiling",))
o.obj("ceiling", "white")
o.poly([(0.3, 1, 0), (1, 1, 0), (1, 1, 1), (0.3, 1, 1)])
o.poly([(0, 1, 0.3), (0.3, 1, 0.3), (0.3, 1, 1), (0, 1, 1)])
o.obj("light", "light")
o.poly([(0, 1, 0), (0.3, 1, 0), (0.3, 1, 0.3), (0, 1, 0.3)])
o.write("corner-light.obj")

# Emitters 1e8 apart in power: a bright green light and a dim red one (different channels, so the
# dim one's light cannot hide in the bright one's rounding).
o = test_box("Extreme: a green light 1e8 times brighter than a red one.")
light(o, (0, 0, 0), 1.0, "bright", "bright_green", 0.1, 0.4)
light(o, (0, 0, 0), 1.0, "dim", "dim_red", 0.6, 0.9)
o.write("bright-dim.obj")

# A single emitter and nothing else: all its power escapes.
o = Obj("Extreme: one emitter and nothing else (all the power escapes).")
light(o, (0, 0, 0), 1.0)
o.write("lone-emitter.obj")

# No emitter: refused with a message.
o = test_box("Extreme: the test box with no light (refused: nothing to solve).")
o.write("no-emitter.obj")

open("extreme.mtl", "w").write("""# Materials of the extreme test scenes.
newmtl white
Kd 0.7 0.7 0.7

newmtl dark
Kd 0.2 0.2 0.2

newmtl light
Kd 0.5 0.5 0.5
Ke 1 1 1

newmtl bright_green
Kd 0 0 0
Ke 0 100000000 0

newmtl dim_red
Kd 0 0 0
Ke 1 0 0
""")
