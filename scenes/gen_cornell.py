def sub(a,b): return [a[i]-b[i] for i in range(3)]
def cross(a,b): return [a[1]*b[2]-a[2]*b[1],a[2]*b[0]-a[0]*b[2],a[0]*b[1]-a[1]*b[0]]
def dot(a,b): return sum(a[i]*b[i] for i in range(3))
def mean(ps): return [sum(p[i] for p in ps)/len(ps) for i in range(3)]
quads = {
 "light": ("light", [(343.0,548.7,227.0),(343.0,548.7,332.0),(213.0,548.7,332.0),(213.0,548.7,227.0)], "down"),
 "floor": ("white", [(552.8,0,0),(0,0,0),(0,0,559.2),(549.6,0,559.2)], "in"),
 "ceiling": ("white", [(556.0,548.8,0),(556.0,548.8,559.2),(0,548.8,559.2),(0,548.8,0)], "in"),
 "back_wall": ("white", [(549.6,0,559.2),(0,0,559.2),(0,548.8,559.2),(556.0,548.8,559.2)], "in"),
 "green_wall": ("green", [(0,0,559.2),(0,0,0),(0,548.8,0),(0,548.8,559.2)], "in"),
 "red_wall": ("red", [(552.8,0,0),(549.6,0,559.2),(556.0,548.8,559.2),(556.0,548.8,0)], "in"),
}
short = [[(130,165,65),(82,165,225),(240,165,272),(290,165,114)],
 [(290,0,114),(290,165,114),(240,165,272),(240,0,272)],
 [(130,0,65),(130,165,65),(290,165,114),(290,0,114)],
 [(82,0,225),(82,165,225),(130,165,65),(130,0,65)],
 [(240,0,272),(240,165,272),(82,165,225),(82,0,225)]]
tall = [[(423,330,247),(265,330,296),(314,330,456),(472,330,406)],
 [(423,0,247),(423,330,247),(472,330,406),(472,0,406)],
 [(472,0,406),(472,330,406),(314,330,456),(314,0,456)],
 [(314,0,456),(314,330,456),(265,330,296),(265,0,296)],
 [(265,0,296),(265,330,296),(423,330,247),(423,0,247)]]
import sys
with_blocks = len(sys.argv) < 2
if with_blocks:
    for n,q in zip(["top","red_side","front","green_side","back"], short): quads["short_block_"+n]=("white",q,"out:short")
    for n,q in zip(["top","red_side","back","green_side","front"], tall): quads["tall_block_"+n]=("white",q,"out:tall")
centre=[278,274.4,279.6]; sc=mean([v for q in short for v in q]); tc=mean([v for q in tall for v in q])
out=["# The measured Cornell box (Cornell Program of Computer Graphics data page), millimetres, y up.",
"# Light lowered 0.1 mm below the ceiling (548.7); red wall triangulated (it is not planar);",
"# reflectances and light radiance: Tungsten RGB values. Faces are wound so that walls face the",
"# interior, blocks face outward and the light faces down." + ("" if with_blocks else " This variant has no blocks."),
"# camera: pos (278 273 -800) dir (0 0 1) up (0 1 0) fov 39.3077",
"mtllib cornell-box.mtl"]
vi=1
for name,(mat,q,mode) in quads.items():
    P=[list(map(float,v)) for v in q]
    n=cross(sub(P[1],P[0]),sub(P[2],P[0])); c=mean(P)
    if mode=="down": want=[0,-1,0]
    elif mode=="in": want=sub(centre,c)
    else: want=sub(c, sc if mode.endswith("short") else tc)
    if dot(n,want)<0: P=P[::-1]
    out.append(f"o {name}"); out.append(f"usemtl {mat}")
    for p in P: out.append("v %g %g %g"%tuple(p))
    if name=="red_wall":
        out.append(f"f {vi} {vi+1} {vi+2}"); out.append(f"f {vi} {vi+2} {vi+3}")
    else:
        out.append(f"f {vi} {vi+1} {vi+2} {vi+3}")
    vi+=4
print("\n".join(out))
