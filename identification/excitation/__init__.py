"""Excitation trajectories for identification: Fourier series and their design."""
