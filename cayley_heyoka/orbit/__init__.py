"""Disturbed elliptic motion in the osculating orbit plane (Cayley 1860), and its Cartesian twin."""
