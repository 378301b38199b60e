"""Triangle meshes for the cell scripts (standard library only): read binary or ASCII STL, OBJ and
COLLADA (DAE) triangles, write binary STL (the one format MuJoCo 2.2.2 reads besides OBJ: it
refuses ASCII STL), make a closed box, split a mesh into its connected parts, and the tight box of a
set of vertices. Units are the files' (the cells use metres).

A mesh is a list of triangles, each a tuple of three (x, y, z) vertices.
"""
import math
import re
import struct


def read_stl(data):
    """The triangles of an STL file's bytes, binary or ASCII."""
    if len(data) >= 84:
        n = struct.unpack("<I", data[80:84])[0]
        if 84 + 50 * n == len(data):
            tris = []
            for i in range(n):
                v = struct.unpack("<12f", data[84 + 50 * i:84 + 50 * i + 48])
                tris.append((v[3:6], v[6:9], v[9:12]))
            return tris
    text = data.decode("ascii", errors="strict")
    verts = [tuple(float(x) for x in m.groups())
             for m in re.finditer(r"vertex\s+(\S+)\s+(\S+)\s+(\S+)", text)]
    if not verts or len(verts) % 3:
        raise ValueError("neither a binary STL nor an ASCII STL with whole triangles")
    return [tuple(verts[i:i + 3]) for i in range(0, len(verts), 3)]


def read_obj(text):
    """The triangles of an OBJ file's text (faces fanned into triangles)."""
    verts, tris = [], []
    for line in text.splitlines():
        f = line.split()
        if not f:
            continue
        if f[0] == "v":
            verts.append(tuple(float(x) for x in f[1:4]))
        elif f[0] == "f":
            idx = [int(x.split("/")[0]) for x in f[1:]]
            idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
            for k in range(1, len(idx) - 1):
                tris.append((verts[idx[0]], verts[idx[k]], verts[idx[k + 1]]))
    return tris


def read_dae(text):
    """The triangles of a COLLADA file's text: every <triangles> or <polylist> of every geometry,
    in the geometry's own frame (node transforms are not applied)."""
    tris = []
    for geo in re.finditer(r"<mesh>(.*?)</mesh>", text, re.S):
        body = geo.group(1)
        sources = {m.group(1): [float(x) for x in m.group(2).split()]
                   for m in re.finditer(r'<source id="([^"]+)".*?<float_array[^>]*>([^<]*)</float_array>',
                                        body, re.S)}
        vmap = {m.group(1): m.group(2).lstrip("#")
                for m in re.finditer(r'<vertices id="([^"]+)">.*?semantic="POSITION" source="([^"]+)"', body, re.S)}
        for prim in re.finditer(r"<(triangles|polylist)\b(.*?)</\1>", body, re.S):
            inner = prim.group(2)
            inputs = re.findall(r'<input semantic="(\w+)" source="#([^"]+)" offset="(\d+)"', inner)
            stride = 1 + max(int(o) for _, _, o in inputs)
            vin = [(s, int(o)) for sem, s, o in inputs if sem == "VERTEX"][0]
            pos = sources[vmap.get(vin[0], vin[0])]
            p = [int(x) for x in re.search(r"<p>([^<]*)</p>", inner).group(1).split()]
            idx = [p[i + vin[1]] for i in range(0, len(p), stride)]
            counts = ([int(x) for x in re.search(r"<vcount>([^<]*)</vcount>", inner).group(1).split()]
                      if prim.group(1) == "polylist" else [3] * (len(idx) // 3))
            at = 0
            for c in counts:
                poly = [tuple(pos[3 * i:3 * i + 3]) for i in idx[at:at + c]]
                for k in range(1, c - 1):
                    tris.append((poly[0], poly[k], poly[k + 1]))
                at += c
    return tris


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def stl_bytes(tris, header):
    """A binary STL of `tris` (float32, normals from the vertex order) with an 80-byte ASCII header:
    the same triangles and header always give the same bytes."""
    head = header.encode("ascii")[:80].ljust(80, b" ")
    out = [head, struct.pack("<I", len(tris))]
    for t in tris:
        n = _cross(_sub(t[1], t[0]), _sub(t[2], t[0]))
        length = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
        n = (0.0, 0.0, 0.0) if length == 0 else tuple(x / length for x in n)
        out.append(struct.pack("<12fH", *n, *t[0], *t[1], *t[2], 0))
    return b"".join(out)


def box_triangles(half, centre=(0.0, 0.0, 0.0)):
    """The 12 triangles of a closed box of half-sizes `half` around `centre`, outward normals."""
    hx, hy, hz = half
    cx, cy, cz = centre
    v = [(cx + sx * hx, cy + sy * hy, cz + sz * hz) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    # v index = 4 * (sx > 0) + 2 * (sy > 0) + (sz > 0); each face as two counter-clockwise triangles.
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = []
    for a, b, c, d in quads:
        tris.append((v[a], v[b], v[c]))
        tris.append((v[a], v[c], v[d]))
    return tris


def components(tris, digits=6):
    """The connected parts of a mesh (triangles sharing a vertex, to `digits` decimals), in the
    order of their first triangle."""
    parent = {}

    def find(a):
        while parent.setdefault(a, a) != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    key = lambda p: tuple(round(x, digits) for x in p)
    for t in tris:
        k0 = find(key(t[0]))
        for p in t[1:]:
            k = find(key(p))
            if k != k0:
                parent[k] = k0
    groups = {}
    for t in tris:
        groups.setdefault(find(key(t[0])), []).append(t)
    return list(groups.values())


def bounds(tris):
    """(lower, upper) corners of the axis-aligned box around the vertices."""
    pts = [p for t in tris for p in t]
    return (tuple(min(p[i] for p in pts) for i in range(3)), tuple(max(p[i] for p in pts) for i in range(3)))


def transform(tris, rotate_z=0.0, shift=(0.0, 0.0, 0.0)):
    """The triangles turned by `rotate_z` [rad] about z, then moved by `shift`."""
    c, s = math.cos(rotate_z), math.sin(rotate_z)
    f = lambda p: (c * p[0] - s * p[1] + shift[0], s * p[0] + c * p[1] + shift[1], p[2] + shift[2])
    return [tuple(f(p) for p in t) for t in tris]


def tight_box(tris, step_deg=0.5):
    """The smallest-volume box around the vertices among those turned about the mesh frame's z-axis
    in steps of `step_deg` (0 .. 90 degrees): (yaw [rad], centre in the mesh frame, half-sizes)."""
    pts = [p for t in tris for p in t]
    best = None
    for k in range(int(round(90 / step_deg))):
        a = math.radians(k * step_deg)
        c, s = math.cos(a), math.sin(a)
        # Coordinates along the box axes (x' = R(a) e_x, y' = R(a) e_y).
        u = [c * p[0] + s * p[1] for p in pts]
        w = [-s * p[0] + c * p[1] for p in pts]
        z = [p[2] for p in pts]
        half = ((max(u) - min(u)) / 2, (max(w) - min(w)) / 2, (max(z) - min(z)) / 2)
        vol = half[0] * half[1] * half[2]
        if best is None or vol < best[0] * (1 - 1e-9):
            mu, mw, mz = (max(u) + min(u)) / 2, (max(w) + min(w)) / 2, (max(z) + min(z)) / 2
            best = (vol, a, (c * mu - s * mw, s * mu + c * mw, mz), half)
    return best[1], best[2], best[3]
