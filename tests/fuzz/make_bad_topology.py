#!/usr/bin/env python3
"""Tet meshes that pass the Medit reader and every per-tet check but are not
an embedding, made from a valid mesh by editing one or a few tets (issue 40):
seeds for the medit and remesh harnesses and the cases of
tests/geometry/remesh/remesh_bad_topology_test.cpp.

Usage: make_bad_topology.py valid.mesh outdir...
"""
import math
import sys


def read(path):
    lines = [l.split() for l in open(path)]
    i, verts, tets = 0, [], []
    while i < len(lines):
        w = lines[i]
        if w and w[0] == "Vertices":
            n = int(lines[i + 1][0])
            verts = [lines[i + 2 + k] for k in range(n)]
            i += 2 + n
        elif w and w[0] == "Tetrahedra":
            n = int(lines[i + 1][0])
            tets = [[int(x) for x in lines[i + 2 + k]] for k in range(n)]
            i += 2 + n
        else:
            i += 1
    return verts, tets


def write(path, verts, tets):
    with open(path, "w") as f:
        f.write("MeshVersionFormatted 2\nDimension 3\n\nVertices\n%d\n" % len(verts))
        for v in verts:
            f.write(" ".join(v) + "\n")
        f.write("\nTetrahedra\n%d\n" % len(tets))
        for t in tets:
            f.write(" ".join(str(x) for x in t) + "\n")
        f.write("\nEnd\n")


def faces(t):
    a, b, c, d = t[:4]
    return [frozenset(x) for x in ((b, c, d), (a, c, d), (a, b, d), (a, b, c))]


def main():
    verts, tets = read(sys.argv[1])
    owners = {}
    for n, t in enumerate(tets):
        for f in faces(t):
            owners.setdefault(f, []).append(n)
    interior = [n for n, t in enumerate(tets) if all(len(owners[f]) == 2 for f in faces(t))]
    t0 = interior[len(interior) // 2]
    cases = {}

    # One vertex index of a tet changed (issue 40): in spheres12.mesh
    # (`synth spheres --size 12`, `mesh -l 6`, 180 tets) the second vertex of
    # tet 101 (0-based) becomes vertex 35 (as in the file, 1-based). Every
    # face stays in at most two tets and no tet is flat; `remesh -l 4` split
    # edges forever on it.
    bad = [list(x) for x in tets]
    overlapping, local, vertex = (101, 1, 35) if len(tets) == 180 else (t0, 3, [v for v in range(1, len(verts) + 1) if v not in tets[t0][:4]][0])
    bad[overlapping][local] = vertex
    cases["overlapping_tet"] = (verts, bad)

    # A vertex of an inner tet moved through the opposite face: that tet and
    # the others around the vertex turn over (each is still a proper tet; the
    # reader and the remesher accept either orientation tet by tet).
    t = tets[t0]
    p = [[float(x) for x in verts[v - 1][:3]] for v in t[:4]]
    centroid = [(p[1][k] + p[2][k] + p[3][k]) / 3 for k in range(3)]
    moved = [list(v) for v in verts]
    moved[t[0] - 1] = ["%.17g" % (2 * centroid[k] - p[0][k] + 0.25 * (centroid[k] - p[0][k])) for k in range(3)] + [verts[t[0] - 1][3]]
    cases["folded_tet"] = (moved, tets)

    # A tet written twice.
    cases["duplicated_tet"] = (verts, tets + [list(tets[t0])])

    # A third tet on an inner face: the face of tet t0 opposite its first
    # vertex, closed again by t0's first vertex.
    cases["face_in_three_tets"] = (verts, tets + [list(tets[t0][1:4]) + [tets[t0][0], tets[t0][4]]])

    # The edge star split in two: a copy of the mesh (new vertex indices)
    # sharing two vertices of an inner edge with it, so that the tets around
    # that edge form two cycles.
    a, b = tets[t0][0], tets[t0][1]
    n = len(verts)
    copy = [[(v if v in (a, b) else v + n) for v in t[:4]] + [t[4]] for t in tets]
    cases["edge_star_in_two_cycles"] = (verts + verts, tets + copy)

    # Two copies of the mesh sharing the two end points of a boundary edge,
    # the second turned by 0.3 rad about that edge: parts touching along an
    # edge, but overlapping.
    a, b = next(sorted(f)[:2] for t in tets for f in faces(t) if len(owners[f]) == 1)
    p = [[float(x) for x in v[:3]] for v in verts]
    axis = [p[b - 1][k] - p[a - 1][k] for k in range(3)]
    norm = math.sqrt(sum(x * x for x in axis))
    axis = [x / norm for x in axis]

    def turned(q, angle=0.3):
        d = [q[k] - p[a - 1][k] for k in range(3)]
        c, s = math.cos(angle), math.sin(angle)
        along = sum(d[k] * axis[k] for k in range(3))
        cross = [axis[1] * d[2] - axis[2] * d[1], axis[2] * d[0] - axis[0] * d[2], axis[0] * d[1] - axis[1] * d[0]]
        return [p[a - 1][k] + d[k] * c + cross[k] * s + axis[k] * along * (1 - c) for k in range(3)]

    second = [["%.17g" % x for x in turned(q)] + [verts[i][3]] for i, q in enumerate(p)]
    copy = [[(v if v in (a, b) else v + n) for v in t[:4]] + [t[4]] for t in tets]
    cases["overlapping_parts_along_an_edge"] = (verts + second, tets + copy)

    for out in sys.argv[2:]:
        for name, (v, t) in cases.items():
            write("%s/%s.mesh" % (out, name), v, t)


main()
