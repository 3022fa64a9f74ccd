"""A local web page to place people in a scan and save them as HA3D placements."""
