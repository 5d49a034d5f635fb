"""Energy-optimal, obstacle-avoiding trajectory planning (paper III.B, III.G)."""
