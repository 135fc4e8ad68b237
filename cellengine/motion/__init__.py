"""The motion layer: robot models, IK, Cartesian paths, collision checking, transit planning,
time parameterisation and the trajectory gate. Pure computation: no driver, no I/O beyond
loading models."""
