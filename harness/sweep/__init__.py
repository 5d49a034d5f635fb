"""Sweeps: the identification error over a grid of robot x noise x seed x method x sample
count, each cell one Ray task (grid, cell, store, run), summarized in tables and figures
(summary, figures)."""
