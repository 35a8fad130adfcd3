"""Studies built on the physics: the load-envelope limit check for CI, the workspace load envelope,
the preload study and the paper's tables."""
