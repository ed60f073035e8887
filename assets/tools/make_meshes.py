#!/usr/bin/python3
"""Procedural surface meshes of the Future Haptic Science Encyclopedia scenes.

Writes closed, consistently (outward) oriented, watertight triangle meshes as OBJ files into
assets/meshes/. Units: metres, sized for a hand at a 5-finger haptic device (8-20 cm).

Every shape is one of two constructions that are watertight and outward oriented by design:
  * a star-shaped surface r(d) over a UV sphere (every ray from the centre meets the surface
    once, so the mesh cannot fold or self-intersect while r > 0), and
  * a generalized tube: rings around a smooth centreline closed by cap rings and a pole vertex
    at each end (the ring frames are parallel-transported so that neighbouring rings do not twist).
core/scene/test/mesh_test.cpp checks every file (each edge shared by exactly two triangles,
positive signed volume, size).

Run with Debian's python3 (numpy from python3-numpy):  /usr/bin/python3 assets/tools/make_meshes.py
The output is deterministic (no random numbers), so re-running it changes no committed file.
"""
import os
import sys

import numpy as np

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "meshes")


def normalize(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def frame_from_axis(axis, hint=(1.0, 0.0, 0.0)):
    """Right-handed orthonormal (e1, e2, e3) with e3 = axis and e1 as close to hint as possible."""
    e3 = normalize(axis)
    h = np.asarray(hint, dtype=float)
    if abs(np.dot(h, e3)) > 0.9:
        h = np.array([0.0, 1.0, 0.0]) if abs(e3[1]) < 0.9 else np.array([0.0, 0.0, 1.0])
    e1 = normalize(h - np.dot(h, e3) * e3)
    e2 = np.cross(e3, e1)
    return e1, e2, e3


# ---------------------------------------------------------------------------------------------
# Constructions


def star_surface(radius, n_lat, n_lon, pole=(0.0, 0.0, 1.0), lon0=(1.0, 0.0, 0.0), warp=1.0,
                 centre=(0.0, 0.0, 0.0)):
    """Star-shaped surface: vertex = centre + radius(d) d over a UV grid of unit directions d.

    radius maps an (N, 3) array of unit directions to N radii [m]. warp > 1 packs the latitude
    rings towards the equator (the plane normal to `pole`), where thin features such as the
    triceratops frill need the resolution.
    """
    e1, e2, e3 = frame_from_axis(pole, lon0)
    u = -1.0 + 2.0 * np.arange(1, n_lat + 1) / (n_lat + 1)
    lat = 0.5 * np.pi * np.sign(u) * np.abs(u) ** warp
    lon = 2.0 * np.pi * np.arange(n_lon) / n_lon
    cl, sl = np.cos(lat)[:, None, None], np.sin(lat)[:, None, None]
    ring = np.cos(lon)[:, None] * e1 + np.sin(lon)[:, None] * e2          # (n_lon, 3)
    dirs = (cl * ring[None, :, :] + sl * e3).reshape(-1, 3)              # ring-major
    dirs = np.vstack([dirs, -e3, e3])                                    # south, north poles
    dirs = normalize(dirs)
    r = np.asarray(radius(dirs), dtype=float)
    if np.any(r <= 0.0):
        raise ValueError("radius must be positive in every direction")
    verts = np.asarray(centre, dtype=float) + r[:, None] * dirs
    return verts, grid_faces(n_lat, n_lon)


def grid_faces(n_rings, n_seg):
    """Triangles of n_rings rings of n_seg vertices (ring-major), then a start pole and an end
    pole. Ring k+1 lies on the side that the right-handed (around-ring, along-axis) pair points
    to, so (a, b, c) below faces outward."""
    faces = []
    s_pole, n_pole = n_rings * n_seg, n_rings * n_seg + 1
    for i in range(n_rings - 1):
        for j in range(n_seg):
            a = i * n_seg + j
            b = i * n_seg + (j + 1) % n_seg
            c = (i + 1) * n_seg + (j + 1) % n_seg
            d = (i + 1) * n_seg + j
            faces.append((a, b, c))
            faces.append((a, c, d))
    last = (n_rings - 1) * n_seg
    for j in range(n_seg):
        faces.append((s_pole, (j + 1) % n_seg, j))
        faces.append((last + j, last + (j + 1) % n_seg, n_pole))
    return np.array(faces, dtype=np.int64)


def tube(centre, radius, n_rings, n_seg, cap_rings=3, start_bulge=0.0, end_bulge=1.0):
    """Generalized tube around the centreline centre(t), t in [0, 1], closed by caps.

    radius(t, phi) [m] may vary around the ring (phi is the angle from the first normal, which
    starts as the component of +z normal to the tangent). Each cap has `cap_rings` extra rings that
    shrink to a pole vertex; bulge 0 gives a flat cap, 1 a hemisphere-like one.
    """
    t = np.linspace(0.0, 1.0, n_rings)
    c = np.array([centre(x) for x in t])
    tangent = np.gradient(c, axis=0)
    tangent = normalize(tangent)
    # Parallel transport of the normal along the centreline (no twist between rings).
    n1 = []
    _, _, _ = frame_from_axis(tangent[0])
    up = np.array([0.0, 0.0, 1.0]) if abs(tangent[0][2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    n = normalize(up - np.dot(up, tangent[0]) * tangent[0])
    for k in range(n_rings):
        n = normalize(n - np.dot(n, tangent[k]) * tangent[k])
        n1.append(n)
    n1 = np.array(n1)
    n2 = np.cross(tangent, n1)      # (n1, n2, tangent) right-handed
    phi = 2.0 * np.pi * np.arange(n_seg) / n_seg
    rows, centres, normals1, normals2 = [], [], [], []

    def ring(ck, a1, a2, rk):
        return ck + rk[:, None] * (np.cos(phi)[:, None] * a1 + np.sin(phi)[:, None] * a2)

    r0 = np.array([radius(0.0, p) for p in phi])
    r1 = np.array([radius(1.0, p) for p in phi])
    # Start cap rings (from the pole side towards the tube), then the tube, then the end cap.
    for m in range(cap_rings, 0, -1):
        s = m / (cap_rings + 1)                     # 0 at the tube, 1 at the pole
        ang = s * 0.5 * np.pi
        off = -tangent[0] * start_bulge * np.mean(r0) * np.sin(ang)
        rows.append(ring(c[0] + off, n1[0], n2[0], r0 * np.cos(ang)))
    for k in range(n_rings):
        rk = np.array([radius(t[k], p) for p in phi])
        rows.append(ring(c[k], n1[k], n2[k], rk))
    for m in range(1, cap_rings + 1):
        s = m / (cap_rings + 1)
        ang = s * 0.5 * np.pi
        off = tangent[-1] * end_bulge * np.mean(r1) * np.sin(ang)
        rows.append(ring(c[-1] + off, n1[-1], n2[-1], r1 * np.cos(ang)))
    start_pole = c[0] - tangent[0] * start_bulge * np.mean(r0)
    end_pole = c[-1] + tangent[-1] * end_bulge * np.mean(r1)
    verts = np.vstack(rows + [start_pole[None, :], end_pole[None, :]])
    return verts, grid_faces(len(rows), n_seg)


def prism(polygon_xy, triangles, z0, z1):
    """Closed prism of a simple counter-clockwise polygon, with its triangulation given."""
    p = np.asarray(polygon_xy, dtype=float)
    n = len(p)
    verts = np.vstack([np.c_[p, np.full(n, z0)], np.c_[p, np.full(n, z1)]])
    faces = []
    for a, b, c in triangles:          # CCW seen from +z: top keeps, bottom flips
        faces.append((n + a, n + b, n + c))
        faces.append((a, c, b))
    for i in range(n):
        j = (i + 1) % n
        faces.append((i, j, n + j))
        faces.append((i, n + j, n + i))
    return verts, np.array(faces, dtype=np.int64)


# ---------------------------------------------------------------------------------------------
# Shape helpers


def ellipsoid_radius(d, a_pos, a_neg, b, c_pos, c_neg):
    """Radius of an egg-like ellipsoid (different semi-axes forward/back and up/down)."""
    ax = np.where(d[:, 0] >= 0, a_pos, a_neg)
    az = np.where(d[:, 2] >= 0, c_pos, c_neg)
    return 1.0 / np.sqrt((d[:, 0] / ax) ** 2 + (d[:, 1] / b) ** 2 + (d[:, 2] / az) ** 2)


def angle_to(d, axis):
    return np.arccos(np.clip(d @ normalize(axis), -1.0, 1.0))


def cone_bump(d, axis, height, width):
    """A conical horn: height [m] at `axis`, falling off linearly to 0 at `width` [rad]."""
    return height * np.clip(1.0 - angle_to(d, axis) / width, 0.0, None) ** 1.5


def smooth_bump(d, axis, height, width):
    return height * np.exp(-(angle_to(d, axis) / width) ** 2)


# ---------------------------------------------------------------------------------------------
# The meshes.  Object frames: x forward (snout, head of the animal), y left, z up.


def triceratops_head():
    # Skull about 15 cm long, frill about 11 cm from the centre: the whole head ~ 20 cm.
    frill_n = normalize([0.8, 0.0, 0.6])        # normal of the frill plate (it rises back-up)
    back_up = normalize([-0.6, 0.0, 0.8])       # middle of the frill fan

    def r(d):
        skull = ellipsoid_radius(d, 0.075, 0.05, 0.042, 0.045, 0.038)
        skull = skull + smooth_bump(d, [0.92, 0.0, -0.39], 0.028, 0.28)     # beak
        skull = skull + cone_bump(d, [0.78, 0.0, 0.62], 0.032, 0.22)        # nose horn
        skull = skull + cone_bump(d, [0.25, 0.42, 0.87], 0.065, 0.2)        # brow horns
        skull = skull + cone_bump(d, [0.25, -0.42, 0.87], 0.065, 0.2)
        # Frill: a scalloped fan in the plate normal to frill_n, behind and above the skull.
        side = d @ frill_n
        fan = np.clip((d @ back_up + 0.35) / 0.6, 0.0, 1.0)
        e1 = back_up
        e2 = np.cross(frill_n, e1)
        psi = np.arctan2(d @ e2, d @ e1)
        edge = 0.1 * (1.0 + 0.05 * np.cos(11.0 * psi))
        frill = edge * fan * np.exp(-(side / 0.11) ** 2)
        return np.maximum(skull, frill)

    return star_surface(r, n_lat=34, n_lon=56, pole=frill_n, lon0=back_up, warp=1.5)


def triceratops_tail():
    # 18 cm long, 3.6 cm thick at the base, tapering and curling slightly down and left.
    def c(t):
        return np.array([-0.18 * t, 0.02 * t * t, -0.03 * t * t])

    def r(t, phi):
        return 0.036 * (1.0 - 0.78 * t) * (1.0 + 0.08 * np.cos(phi))       # deeper than wide

    return tube(c, r, n_rings=36, n_seg=24, cap_rings=2, start_bulge=0.0, end_bulge=0.8)


def triceratops_leg():
    # A front leg standing on the ground: 15 cm tall, thick thigh, narrower shin, wide foot
    # with three toe pads; the sole is flat at z = 0.
    def c(t):
        return np.array([0.01 * np.sin(np.pi * t), 0.0, 0.15 * (1.0 - t)])

    def r(t, phi):
        thigh = 0.038 * np.exp(-((t - 0.1) / 0.35) ** 2)
        shin = 0.024
        foot = 0.012 * np.exp(-((t - 0.97) / 0.08) ** 2)
        toes = 0.008 * np.exp(-((t - 0.97) / 0.06) ** 2) * np.maximum(np.cos(3.0 * phi), 0.0)
        return max(thigh, shin) + foot + toes

    return tube(c, r, n_rings=34, n_seg=28, cap_rings=3, start_bulge=0.6, end_bulge=0.0)


def daphnia_body():
    # Daphnia longispina (1.5 mm) magnified about 100 times: a laterally flattened oval
    # carapace 15 cm long with a rounded head, a belly bulge and a brood pouch on the back.
    def r(d):
        body = ellipsoid_radius(d, 0.075, 0.062, 0.032, 0.048, 0.044)
        body = body + smooth_bump(d, [0.9, 0.0, 0.35], 0.012, 0.35)         # head / helmet
        body = body + smooth_bump(d, [0.1, 0.0, -1.0], 0.008, 0.6)          # belly
        body = body + smooth_bump(d, [-0.35, 0.0, 0.94], 0.006, 0.45)       # brood pouch
        return body

    return star_surface(r, n_lat=28, n_lon=40, pole=[0.0, 1.0, 0.0], lon0=[1.0, 0.0, 0.0],
                        warp=1.0)


def daphnia_spine():
    # The long tail spine (the "horn" a visitor touches): 11 cm, from 1.2 cm thick to 0.25 cm.
    def c(t):
        return np.array([-0.11 * t, 0.0, 0.02 * t - 0.025 * t * t])

    def r(t, phi):
        return 0.006 * (1.0 - 0.8 * t)

    return tube(c, r, n_rings=30, n_seg=16, cap_rings=2, start_bulge=0.0, end_bulge=1.0)


def ball():
    return star_surface(lambda d: np.full(len(d), 0.04), n_lat=20, n_lon=32)


def push_button():
    # Button cap: a cylinder 4 cm across and 1.2 cm high, origin at the centre of its top face.
    return tube(lambda t: np.array([0.0, 0.0, -0.012 * (1.0 - t)]), lambda t, p: 0.02,
                n_rings=4, n_seg=32, cap_rings=3, start_bulge=0.0, end_bulge=0.0)


def lever():
    # Lever handle: a rod 9 cm long (hinge at the origin, along +z) with a knob at the top.
    def r(t, phi):
        return 0.006 + 0.007 * np.exp(-((t - 0.93) / 0.07) ** 2)

    return tube(lambda t: np.array([0.0, 0.0, 0.09 * t]), r, n_rings=24, n_seg=16,
                cap_rings=2, start_bulge=0.0, end_bulge=0.8)


def arrow():
    # A flat arrow 9 cm long pointing along +x, 1 cm thick, its top face at z = 0.
    poly = [(-0.045, -0.012), (0.005, -0.012), (0.005, -0.03), (0.045, 0.0),
            (0.005, 0.03), (0.005, 0.012), (-0.045, 0.012)]
    tris = [(0, 1, 5), (0, 5, 6), (2, 3, 4), (1, 2, 4), (1, 4, 5)]
    return prism(poly, tris, -0.01, 0.0)


def book():
    # A closed book 10 x 14 cm, 3 cm thick, origin at the centre of its top face.
    poly = [(-0.05, -0.07), (0.05, -0.07), (0.05, 0.07), (-0.05, 0.07)]
    return prism(poly, [(0, 1, 2), (0, 2, 3)], -0.03, 0.0)


MESHES = {
    "triceratops_head": (triceratops_head, "triceratops head: skull, beak, nose horn, two brow horns, frill"),
    "triceratops_tail": (triceratops_tail, "triceratops tail, base at the origin (fix x > -0.005 m)"),
    "triceratops_leg": (triceratops_leg, "triceratops front leg, sole at z = 0"),
    "daphnia_body": (daphnia_body, "Daphnia longispina carapace with head, belly and brood pouch"),
    "daphnia_spine": (daphnia_spine, "Daphnia tail spine, base at the origin"),
    "ball": (ball, "ball of radius 4 cm"),
    "button": (push_button, "push-button cap, top face at z = 0"),
    "lever": (lever, "lever handle, hinge at the origin"),
    "arrow": (arrow, "flat arrow pointing along +x, top face at z = 0"),
    "book": (book, "closed book, top face at z = 0"),
}


def signed_volume(v, f):
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    return np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0


def check_closed(f):
    edges = {}
    for tri in f:
        for k in range(3):
            e = (int(tri[k]), int(tri[(k + 1) % 3]))
            edges[e] = edges.get(e, 0) + 1
    for (a, b), n in edges.items():
        if n != 1 or edges.get((b, a), 0) != 1:
            raise RuntimeError("edge %d-%d not shared by exactly two opposite triangles" % (a, b))


def write_obj(path, v, f, comment):
    size = v.max(axis=0) - v.min(axis=0)
    with open(path, "w", encoding="ascii") as out:
        out.write("# %s\n" % comment)
        out.write("# generated by assets/tools/make_meshes.py; units: metres; do not edit\n")
        out.write("# %d vertices, %d triangles, bounding box %.3f x %.3f x %.3f m\n"
                  % (len(v), len(f), size[0], size[1], size[2]))
        for p in v:
            out.write("v %.6f %.6f %.6f\n" % (p[0], p[1], p[2]))
        for t in f:
            out.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))


def main():
    os.makedirs(OUT, exist_ok=True)
    for name, (make, comment) in MESHES.items():
        v, f = make()
        v = np.round(v, 6)                      # what the OBJ holds
        check_closed(f)
        vol = signed_volume(v, f)
        if vol <= 0.0:
            raise RuntimeError("%s: signed volume %g is not positive" % (name, vol))
        write_obj(os.path.join(OUT, name + ".obj"), v, f, comment)
        size = v.max(axis=0) - v.min(axis=0)
        print("%-18s %5d vertices %5d triangles  %5.1f x %5.1f x %5.1f cm  volume %7.1f cm^3"
              % (name, len(v), len(f), *(100 * size), vol * 1e6))
    return 0


if __name__ == "__main__":
    sys.exit(main())
