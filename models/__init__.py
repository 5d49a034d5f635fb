"""MJCF and URDF models of the robots torquebench ships, one folder per robot.

Installed as package data, so the files are found wherever the package is
installed (site-packages or this checkout); `MODELS / "<robot>" / "<file>"`.
"""

from pathlib import Path

MODELS = Path(__file__).resolve().parent
