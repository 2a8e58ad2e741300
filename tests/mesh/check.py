"""Independent checks of mesh files written by `kardia mesh` (run by tests/it/mesh.rs).

For each file given: trimesh reads it (STL, OBJ, PLY; a 3MF's model XML is read here with
the standard library and handed to trimesh) and must find it watertight and winding
consistent with a positive volume; manifold3d must accept it as a manifold. Prints one line
per file and exits 1 on the first complaint.
"""

import sys
import zipfile
import xml.etree.ElementTree as ET

import numpy as np
import trimesh
import manifold3d


def load(path):
    if path.lower().endswith(".3mf"):
        with zipfile.ZipFile(path) as z:
            root = ET.fromstring(z.read("3D/3dmodel.model"))
        ns = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}
        if root.get("unit") != "millimeter":
            raise SystemExit(f"{path}: unit is {root.get('unit')!r}, not millimeter")
        if root.find(".//m:basematerials/m:base", ns) is None:
            raise SystemExit(f"{path}: no colour (basematerials)")
        v = [[float(e.get(k)) for k in "xyz"] for e in root.iterfind(".//m:vertex", ns)]
        f = [[int(e.get(k)) for k in ("v1", "v2", "v3")] for e in root.iterfind(".//m:triangle", ns)]
        return trimesh.Trimesh(np.array(v), np.array(f), process=True)
    return trimesh.load(path, force="mesh", process=True)


def check(path):
    mesh = load(path)
    problems = []
    if not mesh.is_watertight:
        problems.append("trimesh: not watertight")
    if not mesh.is_winding_consistent:
        problems.append("trimesh: winding not consistent")
    if not mesh.volume > 0:
        problems.append(f"trimesh: volume {mesh.volume} not positive")
    m = manifold3d.Manifold(
        manifold3d.Mesh(
            vert_properties=np.asarray(mesh.vertices, dtype=np.float32),
            tri_verts=np.asarray(mesh.faces, dtype=np.uint32),
        )
    )
    if m.status() != manifold3d.Error.NoError:
        problems.append(f"manifold3d: {m.status()}")
    elif m.is_empty():
        problems.append("manifold3d: empty")
    if problems:
        print(f"{path}: " + "; ".join(problems))
        return False
    print(
        f"{path}: ok ({len(mesh.faces)} triangles, volume {mesh.volume:.6g}, "
        f"manifold3d volume {m.volume():.6g}, genus {m.genus()})"
    )
    return True


if __name__ == "__main__":
    ok = all([check(p) for p in sys.argv[1:]])
    sys.exit(0 if ok else 1)
