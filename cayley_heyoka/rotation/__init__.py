"""The rotation family: a rigid body about a fixed point (Cayley 1843, 1846; Euler 1758)."""
