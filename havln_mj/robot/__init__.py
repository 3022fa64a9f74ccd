"""Robot models and controllers: the kinematic point body's rig and the GO1 quadruped."""
