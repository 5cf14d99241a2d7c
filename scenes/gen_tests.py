def faces(lo, hi):
    # inward-facing quads of a box, as (name, [4 corners]) with CCW winding seen from inside
    x0,y0,z0=lo; x1,y1,z1=hi
    return [
     ("floor",   [(x0,y0,z0),(x0,y0,z1),(x1,y0,z1),(x1,y0,z0)]),
     ("ceiling", [(x0,y1,z0),(x1,y1,z0),(x1,y1,z1),(x0,y1,z1)]),
     ("wall_x0", [(x0,y0,z0),(x0,y1,z0),(x0,y1,z1),(x0,y0,z1)]),
     ("wall_x1", [(x1,y0,z0),(x1,y0,z1),(x1,y1,z1),(x1,y1,z0)]),
     ("wall_z0", [(x0,y0,z0),(x1,y0,z0),(x1,y1,z0),(x0,y1,z0)]),
     ("wall_z1", [(x0,y0,z1),(x0,y1,z1),(x1,y1,z1),(x1,y0,z1)]),
    ]
def sub(a,b): return [a[i]-b[i] for i in range(3)]
def cross(a,b): return [a[1]*b[2]-a[2]*b[1],a[2]*b[0]-a[0]*b[2],a[0]*b[1]-a[1]*b[0]]
def check(q, centre):
    n=cross(sub(q[1],q[0]),sub(q[2],q[0])); c=[sum(p[i] for p in q)/4 for i in range(3)]
    assert sum(n[i]*(centre[i]-c[i]) for i in range(3))>0, q
def write(path, header, s, mat, strips=0, strip_faces=("floor",)):
    out=[f"# {header}", "mtllib test-scenes.mtl"]; vi=1
    for name,q in faces((0,0,0),(s,s,s)):
        check(q,(s/2,s/2,s/2))
        out += [f"o {name}", f"usemtl {mat}"]
        if strips and name in strip_faces:
            a,b,c,d=q
            for k in range(strips):
                t0=k/strips; t1=(k+1)/strips
                lerp=lambda p,r,t:[p[i]+(r[i]-p[i])*t for i in range(3)]
                p0=lerp(a,b,t0); p1=lerp(a,b,t1); p2=lerp(d,c,t1); p3=lerp(d,c,t0)
                for p in (p0,p1,p2,p3): out.append("v %.9g %.9g %.9g"%tuple(p))
                out.append(f"f {vi} {vi+1} {vi+2}"); out.append(f"f {vi} {vi+2} {vi+3}"); vi+=4
        else:
            for p in q: out.append("v %.9g %.9g %.9g"%tuple(p))
            out.append(f"f {vi} {vi+1} {vi+2} {vi+3}"); vi+=4
    # light: 0.3 x 0.3 square under the ceiling, facing down
    h=s*(1-1e-3); a=0.35*s; b=0.65*s
    out += ["o light","usemtl light"]
    for p in [(a,h,a),(b,h,a),(b,h,b),(a,h,b)]: out.append("v %.9g %.9g %.9g"%p)
    out.append(f"f {vi} {vi+1} {vi+2} {vi+3}")
    open(path,"w").write("\n".join(out)+"\n")
write("stiff-box.obj","Stiff scene: closed unit box, reflectance 0.98, small light under the ceiling.",1.0,"nearwhite")
write("huge-box.obj","Extreme scale: the closed test box at 2^17 = 131072 units (a power of two, so results must match the tiny box exactly).",131072.0,"white")
write("tiny-box.obj","Extreme scale: the closed test box at 2^-13 = 0.0001220703125 units.",2.0**-13,"white")
write("slivers.obj","Long thin triangles: the closed test box with its floor cut into 300 strips (aspect 300:1).",1.0,"white",strips=300)
open("test-scenes.mtl","w").write("""# Materials of the stiff and extreme test scenes.
newmtl white
Kd 0.7 0.7 0.7

newmtl nearwhite
Kd 0.98 0.98 0.98

newmtl light
Kd 0.5 0.5 0.5
Ke 1 1 1
""")
