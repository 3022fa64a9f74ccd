"""MuJoCo geom groups, one meaning each, shared by the world builder and the renderer."""

VISUAL = 0  # building visual mesh: rendered by agent cameras
ROBOT = 1  # robot body geoms
HUMANS = 2  # people (mocap bodies, no contact)
COLLISION = 3  # building collision boxes / hulls: hidden from cameras
LABELS = 4  # untextured copies of labelled objects, drawn only by the segmentation pass

CAMERA_GROUPS = (VISUAL, ROBOT, HUMANS)
