"""Real measured logs shipped with torquebench, one folder per log, each with its licence
and a README recording its provenance and how it was converted.

Installed as package data, so the files are found wherever the package is installed
(site-packages or this checkout): `DATA / "<log>" / "<file>"`.
"""

from pathlib import Path

DATA = Path(__file__).resolve().parent
