# Writes scenes/cornell_box.{obj,mtl,gltf} from the published Cornell box data (millimetres ->
# metres). Python 3 standard library only; run from the repository root:
#     python3 tools/cornell_box.py
# The glTF holds the same vertices as f32 (what the OBJ loader reads), and the same triangles
# (each face fanned from its first corner, as the OBJ loader triangulates it).
import json, struct, base64

def sub(a,b): return [a[i]-b[i] for i in range(3)]
def cross(a,b): return [a[1]*b[2]-a[2]*b[1], a[2]*b[0]-a[0]*b[2], a[0]*b[1]-a[1]*b[0]]
def dot(a,b): return sum(a[i]*b[i] for i in range(3))
def mean(vs): return [sum(v[i] for v in vs)/len(vs) for i in range(3)]

def P(*xs): return [tuple(x/1000.0 for x in xs[i:i+3]) for i in range(0, len(xs), 3)]

room_center = [278.0/1000, 274.4/1000, 279.6/1000]
objects = []  # (name, material, vertices, faces(list of index lists))

def quad(name, mat, pts, inward=True):
    objects.append((name, mat, pts, [[0, 1, 2, 3]]))

quad("floor", "white", P(552.8,0,0, 0,0,0, 0,0,559.2, 549.6,0,559.2))
quad("ceiling", "white", P(556.0,548.8,0, 556.0,548.8,559.2, 0,548.8,559.2, 0,548.8,0))
quad("back_wall", "white", P(549.6,0,559.2, 0,0,559.2, 0,548.8,559.2, 556.0,548.8,559.2))
quad("right_wall", "green", P(0,0,559.2, 0,0,0, 0,548.8,0, 0,548.8,559.2))
quad("left_wall", "red", P(552.8,0,0, 549.6,0,559.2, 556.0,548.8,559.2, 556.0,548.8,0))
# The light, 0.1 mm below the ceiling (548.7 instead of the ceiling's 548.8), facing down.
quad("light", "light", P(343.0,548.7,227.0, 343.0,548.7,332.0, 213.0,548.7,332.0, 213.0,548.7,227.0))

def block(name, top, h):
    n = len(top)
    verts = [(x/1000, h/1000, z/1000) for (x, z) in top] + [(x/1000, 0.0, z/1000) for (x, z) in top]
    faces = [list(range(n)), list(reversed(range(n, 2*n)))]
    for i in range(n):
        j = (i + 1) % n
        faces.append([n + i, n + j, j, i])
    objects.append((name, "white", verts, faces))

block("short_block", [(130,65), (82,225), (240,272), (290,114)], 165.0)
block("tall_block", [(423,247), (265,296), (314,456), (472,406)], 330.0)

def normal(v, f):
    a, b, c = (v[i] for i in f[:3])
    return cross(sub(b, a), sub(c, a))

# Fix orientations: walls face the room, blocks face outwards, the light faces down.
fixed = []
for name, mat, v, faces in objects:
    out = []
    centroid = mean(v)
    for f in faces:
        n = normal(v, f)
        fc = mean([v[i] for i in f])
        if name == "light":
            want = n[1] < 0
        elif name.endswith("block"):
            want = dot(n, sub(fc, centroid)) > 0
        else:
            want = dot(n, sub(room_center, fc)) > 0
        out.append(f if want else list(reversed(f)))
        if not want:
            print("flipped", name, f)
    fixed.append((name, mat, v, out))
objects = fixed

def fmt(x):
    s = ("%.4f" % x).rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s

hdr = """# The Cornell box: the published geometry of the Cornell University Program of Computer
# Graphics ("Cornell Box Data": floor, ceiling, back, left and right walls, short and tall
# blocks, light), in metres (the published millimetres / 1000). Two changes: the light is 0.1 mm
# below the ceiling (y = 0.5487, not 0.5488), so that the two do not share a plane, and the
# blocks are closed by bottom faces on the floor, so that each is a convex solid.
# Faces are counter-clockwise seen from the side they face: walls, floor and ceiling face the
# room, the blocks face outwards, the light faces down. No normals: flat faces.
# Camera of the published data: eye (0.278, 0.273, -0.8) looking along +z, up +y, 35 mm focal
# length on a 25 mm x 25 mm film (a 39.3 degree field of view).
# Written by tools/cornell_box.py; also as cornell_box.gltf (identical geometry).
"""
with open("scenes/cornell_box.obj", "w") as o:
    o.write(hdr)
    o.write("mtllib cornell_box.mtl\n")
    base = 1
    for name, mat, v, faces in objects:
        o.write("\no %s\nusemtl %s\n" % (name, mat))
        for p in v:
            o.write("v %s %s %s\n" % tuple(fmt(x) for x in p))
        for f in faces:
            o.write("f " + " ".join(str(base + i) for i in f) + "\n")
        base += len(v)

with open("scenes/cornell_box.mtl", "w") as o:
    o.write("""# Materials of cornell_box.obj: diffuse reflectances (RGB approximations of the measured
# spectra in common use), a dielectric specular of 0.04 at full roughness (Ns 0), as in the glTF
# version; the light emits Ke (radiance, linear RGB).
newmtl white
Kd 0.73 0.73 0.73
Ks 0.04 0.04 0.04
Ns 0

newmtl red
Kd 0.63 0.065 0.05
Ks 0.04 0.04 0.04
Ns 0

newmtl green
Kd 0.14 0.45 0.091
Ks 0.04 0.04 0.04
Ns 0

newmtl light
Kd 0.78 0.78 0.78
Ks 0.04 0.04 0.04
Ns 0
Ke 17 12 4
""")

# glTF: one mesh per object, one triangles primitive each, indices as the OBJ loader fans them.
mats = {"white": [0.73, 0.73, 0.73], "red": [0.63, 0.065, 0.05], "green": [0.14, 0.45, 0.091], "light": [0.78, 0.78, 0.78]}
mat_names = list(mats)
buf = bytearray()
accessors, views, meshes, nodes = [], [], [], []
def add_view(data, target):
    while len(buf) % 4: buf.append(0)
    off = len(buf); buf.extend(data)
    views.append({"buffer": 0, "byteOffset": off, "byteLength": len(data), "target": target})
    return len(views) - 1
for name, mat, v, faces in objects:
    pos = [[struct.unpack('<f', struct.pack('<f', float(fmt(x))))[0] for x in p] for p in v]
    tris = []
    for f in faces:
        for k in range(1, len(f) - 1):
            tris.append([f[0], f[k], f[k+1]])
    idx = [i for t in tris for i in t]
    pv = add_view(b''.join(struct.pack('<3f', *p) for p in pos), 34962)
    accessors.append({"bufferView": pv, "componentType": 5126, "count": len(v), "type": "VEC3",
                      "min": [min(p[i] for p in pos) for i in range(3)], "max": [max(p[i] for p in pos) for i in range(3)]})
    pa = len(accessors) - 1
    iv = add_view(struct.pack('<%dH' % len(idx), *idx), 34963)
    accessors.append({"bufferView": iv, "componentType": 5123, "count": len(idx), "type": "SCALAR"})
    ia = len(accessors) - 1
    meshes.append({"name": name, "primitives": [{"attributes": {"POSITION": pa}, "indices": ia, "material": mat_names.index(mat), "mode": 4}]})
    nodes.append({"name": name, "mesh": len(meshes) - 1})
materials = []
for m in mat_names:
    d = {"name": m, "pbrMetallicRoughness": {"baseColorFactor": mats[m] + [1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}}
    if m == "light":
        d["emissiveFactor"] = [1.0, 12.0 / 17.0, 4.0 / 17.0]
        d["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": 17.0}}
    materials.append(d)
gltf = {
    "asset": {"version": "2.0", "generator": "arealight scenes/ generator",
              "copyright": "Geometry: Cornell Box Data, Cornell University Program of Computer Graphics"},
    "extensionsUsed": ["KHR_materials_emissive_strength"],
    "scene": 0,
    "scenes": [{"name": "cornell_box", "nodes": list(range(len(nodes)))}],
    "nodes": nodes, "meshes": meshes, "materials": materials,
    "accessors": accessors, "bufferViews": views,
    "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(buf)).decode()}],
}
with open("scenes/cornell_box.gltf", "w") as o:
    json.dump(gltf, o, indent=1)
    o.write("\n")
print(len(objects), "objects", len(buf), "bytes")
