"""Matterport3D scans from the user's licensed copy.

``layout`` finds a scan's files (raw release or habitat layout), ``house`` parses the
``.house`` region annotations, and ``frame`` checks that a mesh and a connectivity graph share
one frame.
"""
