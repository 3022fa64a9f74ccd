"""Agent bodies: the kinematic point body (and, later, the GO1 quadruped)."""
