"""File names of the scan-folder contract (one folder per building)."""

MESH_GLB = "mesh.glb"  # or MESH_OBJ (+ .mtl and textures)
MESH_OBJ = "mesh.obj"
CONNECTIVITY = "connectivity.json"  # exact Matterport3DSimulator schema
REGIONS = "regions.json"  # levels, regions, objects, viewpoint -> region
BOXES = "boxes.json"  # optional exact box geometry (procedural houses)
META = "scan.json"  # scene id, kind, provenance
