#!/usr/bin/python3
"""Writes the Gmsh meshes of data/spatial/meshes with Debian's python3-gmsh (Gmsh 4.8, MSH 4.1
ASCII): `/usr/bin/python3 data/spatial/meshes/make_meshes.py`. Checked in, so that the tests do
not need Gmsh; rerun it after changing this script.

cube_tets.msh  the unit cube in tetrahedra (size 0.2), physical surfaces "bottom" (z = 0) and
               "top" (z = 1) and the physical volume "cube"
beam_hex.msh   the beam 10 x 1 x 1 in 20 x 1 x 1 hexahedra (transfinite, recombined), physical
               surfaces "root" (x = 0) and "tip" (x = 10)
"""
import pathlib

import gmsh

HERE = pathlib.Path(__file__).resolve().parent


def surfaces_at(axis, value):
    tol = 1e-6
    out = []
    for dim, tag in gmsh.model.getEntities(2):
        lo = gmsh.model.getBoundingBox(dim, tag)
        if abs(lo[axis] - value) < tol and abs(lo[axis + 3] - value) < tol:
            out.append(tag)
    return out


def group(dim, tags, name):
    gmsh.model.setPhysicalName(dim, gmsh.model.addPhysicalGroup(dim, tags), name)


def cube_tets():
    gmsh.model.add("cube_tets")
    gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
    gmsh.model.occ.synchronize()
    group(2, surfaces_at(2, 0.0), "bottom")
    group(2, surfaces_at(2, 1.0), "top")
    group(3, [1], "cube")
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.2)
    gmsh.model.mesh.generate(3)
    gmsh.write(str(HERE / "cube_tets.msh"))


def beam_hex():
    gmsh.model.add("beam_hex")
    gmsh.model.occ.addBox(0, -0.5, -0.5, 10, 1, 1)
    gmsh.model.occ.synchronize()
    for dim, tag in gmsh.model.getEntities(1):
        lo = gmsh.model.getBoundingBox(dim, tag)
        along_x = abs(lo[3] - lo[0]) > 1
        gmsh.model.mesh.setTransfiniteCurve(tag, 21 if along_x else 2)
    for dim, tag in gmsh.model.getEntities(2):
        gmsh.model.mesh.setTransfiniteSurface(tag)
        gmsh.model.mesh.setRecombine(dim, tag)
    gmsh.model.mesh.setTransfiniteVolume(1)
    group(2, surfaces_at(0, 0.0), "root")
    group(2, surfaces_at(0, 10.0), "tip")
    group(3, [1], "beam")
    gmsh.model.mesh.generate(3)
    gmsh.write(str(HERE / "beam_hex.msh"))


gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
cube_tets()
beam_hex()
gmsh.finalize()
