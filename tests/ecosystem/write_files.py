"""Writes one shape, one outline and meshes in every way the field's programs save them at
their defaults (PyVista/VTK, meshio, Gmsh), plus what each should hold, for the ecosystem
test (tests/it/ecosystem.rs). Usage: python write_files.py OUT_DIR [GMSH]"""

import json
import os
import subprocess
import sys

import meshio
import numpy as np
import pyvista as pv
import vtk

out = sys.argv[1]
gmsh = sys.argv[2] if len(sys.argv) > 2 else "gmsh"
os.makedirs(out, exist_ok=True)
manifest = []


def record(name, kind, points, cells, refuse=None):
    manifest.append(
        {
            "file": name,
            "kind": kind,
            "points": np.asarray(points, dtype=float).tolist(),
            "cells": np.asarray(cells, dtype=int).tolist(),
            "refuse": refuse,
        }
    )


# A closed triangle surface, not a unit shape: a bumpy ellipsoid in mm.
sphere = pv.Sphere(radius=20.0, theta_resolution=24, phi_resolution=16)
p = sphere.points.astype(float)
p[:, 0] *= 1.6
p[:, 2] += 2.0 * np.sin(p[:, 0] / 7.0)
surface = pv.PolyData(p, sphere.faces)
tri = surface.faces.reshape(-1, 4)[:, 1:]
pts = np.asarray(surface.points, dtype=float)


def save_surface(name, **kw):
    surface.copy().save(os.path.join(out, name), **kw)
    record(name, "surface", pts, tri)


save_surface("pyvista_default.vtp")
save_surface("pyvista_ascii.vtp", binary=False)
save_surface("pyvista_lz4.vtp", compression="lz4")
save_surface("pyvista_uncompressed.vtp", compression=None)
save_surface("pyvista_default.vtk")
save_surface("pyvista_ascii.vtk", binary=False)
surface.copy().save(os.path.join(out, "pyvista_lzma.vtp"), compression="lzma")
record("pyvista_lzma.vtp", "surface", pts, tri, refuse="LZMA")

# VTK's own writers: appended raw and base64 data, UInt32 headers, big-endian; legacy 4.2.
for name, setup in [
    ("vtk_appended_raw.vtp", lambda w: (w.SetDataModeToAppended(), w.EncodeAppendedDataOff())),
    ("vtk_appended_base64.vtp", lambda w: (w.SetDataModeToAppended(), w.EncodeAppendedDataOn())),
    ("vtk_uint32_bigendian.vtp", lambda w: (w.SetHeaderTypeToUInt32(), w.SetByteOrderToBigEndian(), w.SetDataModeToBinary())),
    ("vtk_appended_uint32_zlib.vtp", lambda w: (w.SetHeaderTypeToUInt32(), w.SetCompressorTypeToZLib(), w.SetDataModeToAppended(), w.EncodeAppendedDataOff())),
]:
    w = vtk.vtkXMLPolyDataWriter()
    w.SetInputData(surface)
    w.SetFileName(os.path.join(out, name))
    setup(w)
    w.Write()
    record(name, "surface", pts, tri)
w = vtk.vtkPolyDataWriter()
w.SetInputData(surface)
w.SetFileName(os.path.join(out, "vtk_legacy42.vtk"))
w.SetFileVersion(42)
w.SetFileTypeToBinary()
w.Write()
record("vtk_legacy42.vtk", "surface", pts, tri)

# Triangle strips (VTK's stripper): the same surface, as triangles again once read.
strips = surface.strip()
strips.save(os.path.join(out, "pyvista_strips.vtp"))
record("pyvista_strips.vtp", "surface_area", pts, tri)

# meshio's defaults for a surface.
m = meshio.Mesh(pts, [("triangle", tri)])
for name in ["meshio_default.vtk", "meshio_default.ply", "meshio_default.stl", "meshio_default.obj"]:
    meshio.write(os.path.join(out, name), m)
    record(name, "surface", pts, tri)

# A 2D outline: a closed polyline in the plane z = 0 (mm).
t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
outline = np.c_[30 * np.cos(t), 12 * np.sin(t) + 3 * np.sin(3 * t), np.zeros_like(t)]
segs = np.c_[np.arange(60), (np.arange(60) + 1) % 60]
line = pv.PolyData(outline, lines=np.c_[np.full(60, 2), segs].ravel())
line.save(os.path.join(out, "pyvista_outline.vtp"))
record("pyvista_outline.vtp", "outline", outline[:, :2], segs)
line.save(os.path.join(out, "pyvista_outline.vtk"))
record("pyvista_outline.vtk", "outline", outline[:, :2], segs)
meshio.write(os.path.join(out, "meshio_outline.vtu"), meshio.Mesh(outline, [("line", segs)]))

# Hexahedra: a 3 x 2 x 2 block, its points deformed (mm), with boundary quads and vertices
# as extra cells where a writer keeps them.
g = np.stack(np.meshgrid(np.arange(4), np.arange(3), np.arange(3), indexing="ij"), -1).reshape(-1, 3)
idx = {tuple(v): i for i, v in enumerate(g)}
nodes = g.astype(float) * 5.0
nodes[:, 2] += 0.3 * nodes[:, 0]
hexes = []
for i in range(3):
    for j in range(2):
        for k in range(2):
            c = [(i, j, k), (i + 1, j, k), (i + 1, j + 1, k), (i, j + 1, k)]
            hexes.append([idx[v] for v in c] + [idx[(a, b, cc + 1)] for a, b, cc in c])
hexes = np.array(hexes)
grid = pv.UnstructuredGrid({pv.CellType.HEXAHEDRON: hexes}, nodes)
for name, kw in [
    ("pyvista_hex_default.vtu", {}),
    ("pyvista_hex_ascii.vtu", {"binary": False}),
    ("pyvista_hex_lz4.vtu", {"compression": "lz4"}),
    ("pyvista_hex_default.vtk", {}),
    ("pyvista_hex_ascii.vtk", {"binary": False}),
]:
    grid.save(os.path.join(out, name), **kw)
    record(name, "mesh", nodes, hexes)
hm = meshio.Mesh(nodes, [("hexahedron", hexes)])
for name, kw in [
    ("meshio_hex_default.vtu", {}),
    ("meshio_hex_default.vtk", {}),
    # (meshio takes .msh for ANSYS unless told Gmsh.)
    ("meshio_hex_default.msh", {"file_format": "gmsh"}),
    ("meshio_hex_ascii.msh", {"file_format": "gmsh", "binary": False}),
    ("meshio_hex_22.msh", {"file_format": "gmsh22"}),
    ("meshio_hex_22_ascii.msh", {"file_format": "gmsh22", "binary": False}),
]:
    meshio.write(os.path.join(out, name), hm, **kw)
    record(name, "mesh", nodes, hexes)
meshio.vtk.write(os.path.join(out, "meshio_hex_42.vtk"), hm, fmt_version="4.2")
record("meshio_hex_42.vtk", "mesh", nodes, hexes)
# Mixed cells: vertices and lines dropped, hexahedra kept; hexahedra with wedges refused.
mixed = meshio.Mesh(nodes, [("vertex", [[0], [1]]), ("line", [[0, 1]]), ("hexahedron", hexes)])
for name in ["meshio_mixed.vtu", "meshio_mixed.vtk"]:
    meshio.write(os.path.join(out, name), mixed)
    record(name, "mesh", nodes, hexes)
wedge = meshio.Mesh(nodes, [("hexahedron", hexes[:2]), ("wedge", [[0, 1, 3, 12, 13, 15]])])
meshio.write(os.path.join(out, "meshio_hex_wedge.vtu"), wedge)
record("meshio_hex_wedge.vtu", "mesh", nodes, hexes[:2], refuse="wedge")

# Gmsh itself: a tetrahedral mesh of a box, binary and ASCII, 4.1 and 2.2, with physical
# groups (a volume and a face).
geo = os.path.join(out, "box.geo")
with open(geo, "w") as f:
    f.write(
        'SetFactory("OpenCASCADE");\nBox(1) = {0, 0, 0, 30, 20, 10};\n'
        'Physical Volume("bone") = {1};\nPhysical Surface("base") = {5};\n'
        "Mesh.MeshSizeMax = 6;\n"
    )
for name, opts in [
    ("gmsh_bin.msh", ["-bin"]),
    ("gmsh_ascii.msh", []),
    ("gmsh_bin22.msh", ["-bin", "-format", "msh22"]),
    ("gmsh_ascii22.msh", ["-format", "msh22"]),
]:
    subprocess.run([gmsh, "-3", geo, "-o", os.path.join(out, name), "-v", "0"] + opts, check=True)
ref = meshio.read(os.path.join(out, "gmsh_ascii.msh"))
tets = ref.get_cells_type("tetra")
used = np.unique(tets)
for name in ["gmsh_bin.msh", "gmsh_ascii.msh", "gmsh_bin22.msh", "gmsh_ascii22.msh"]:
    # Gmsh keeps geometry nodes not used by the tetrahedra; atlasmesh keeps every node too.
    record(name, "gmsh", ref.points, tets)
os.remove(geo)

with open(os.path.join(out, "manifest.json"), "w") as f:
    json.dump(manifest, f)
print(len(manifest), "files")
