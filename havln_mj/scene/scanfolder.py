"""File names of the scan-folder contract (one folder per building)."""

MESH_GLB = "mesh.glb"  # or MESH_OBJ (+ .mtl and textures)
MESH_OBJ = "mesh.obj"
CONNECTIVITY = "connectivity.json"  # exact Matterport3DSimulator schema
REGIONS = "regions.json"  # levels, regions, objects, viewpoint -> region
BOXES = "boxes.json"  # optional exact box geometry (procedural houses, graph proxies)
ROUTES = "routes.json"  # optional: edges walked by a route, not straight (graph proxies)
META = "scan.json"  # scene id, kind, provenance
SEMANTICS = "semantics.json"  # optional: each mesh part's mpcat40 class and object instance
MANIFEST = "manifest.json"
"""A cached scan's manifest of its inputs and files (see :mod:`~havln_mj.scene.cache_keys`)."""
