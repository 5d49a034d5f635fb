"""A robot's collision (or visual) geometry as points: what the link capsules
(harness.robots.capsules) and the bodies' ellipsoids (harness.robots.ellipsoids) are fitted to.

Each body's URDF <collision> (or <visual>) elements: STL meshes, boxes, cylinders, spheres,
at q = 0, bodies fixed to it included. A body without geometry the harness can read (none,
an MJCF, a mesh format other than STL) has no points.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

SPHERE_DIRECTIONS = 26  # points on a sphere or cylinder rim standing for its surface


def read_stl(path: Path) -> np.ndarray:
    """Vertices (n, 3) of a binary or ASCII STL file (its units)."""
    data = path.read_bytes()
    if data[:5].lower() == b"solid" and b"facet" in data[:400]:
        rows = [line.split()[1:4] for line in data.decode(errors="replace").splitlines()
                if line.strip().startswith("vertex")]
        return np.array(rows, float).reshape(-1, 3)
    count = int(np.frombuffer(data[80:84], "<u4")[0])
    triangles = np.frombuffer(data[84:84 + 50 * count], np.dtype(
        [("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")]))
    return triangles["vertices"].reshape(-1, 3).astype(float)


def _resolve(filename: str, urdf: Path, packages: tuple[Path, ...]) -> Path | None:
    """The file a URDF mesh reference names (package://, file:// or relative), if found."""
    if filename.startswith("file://"):
        path = Path(filename[7:])
        return path if path.is_file() else None
    if filename.startswith("package://"):
        rest = filename[len("package://"):]
        candidates = [root / rest for root in (*packages, *urdf.parents)]
        candidates += [root / rest.split("/", 1)[-1] for root in urdf.parents]
        return next((c for c in candidates if c.is_file()), None)
    path = urdf.parent / filename
    return path if path.is_file() else None


def _sphere(radius: float) -> np.ndarray:
    directions = np.array([(x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1)
                           if (x, y, z) != (0, 0, 0)], float)
    return radius * directions / np.linalg.norm(directions, axis=1, keepdims=True)


def _points(geometry: ET.Element, urdf: Path, packages: tuple[Path, ...]) -> np.ndarray | None:
    """Points (n, 3) in the collision element's frame standing for its surface (None:
    unreadable)."""
    shape = next(iter(geometry), None)
    if shape is None:
        return None
    if shape.tag == "mesh":
        path = _resolve(shape.get("filename", ""), urdf, packages)
        if path is None or path.suffix.lower() != ".stl":
            return None
        scale = np.array([float(v) for v in shape.get("scale", "1 1 1").split()])
        return read_stl(path) * scale
    if shape.tag == "box":
        half = np.array([float(v) for v in shape.get("size").split()]) / 2
        return np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
    if shape.tag == "sphere":
        return _sphere(float(shape.get("radius")))
    if shape.tag in ("cylinder", "capsule"):
        r, half = float(shape.get("radius")), float(shape.get("length")) / 2
        rim = _sphere(r) * [1, 1, 0]
        ends = [half + r, -half - r] if shape.tag == "capsule" else [half, -half]
        return np.vstack([rim + [0, 0, z] for z in (half, -half)] + [[[0, 0, z]] for z in ends])
    return None


def _placement(element: ET.Element | None) -> pin.SE3:
    if element is None:
        return pin.SE3.Identity()
    xyz = np.array([float(v) for v in element.get("xyz", "0 0 0").split()])
    rpy = [float(v) for v in element.get("rpy", "0 0 0").split()]
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), xyz)


def body_points(urdf: Path, model: pin.Model, packages: tuple[Path, ...] = (),
                kind: str = "collision") -> dict[int, np.ndarray]:
    """Per joint of model (1-based) carrying any, the points (n, 3) standing for the surface
    of the URDF's `kind` ("collision" or "visual") geometry of the links it carries (links
    fixed to it included), in that joint's frame (m)."""
    out: dict[int, list[np.ndarray]] = {}
    for link in ET.parse(urdf).getroot().iter("link"):
        name = link.get("name")
        if not model.existFrame(name, pin.FrameType.BODY):
            continue
        frame = model.frames[model.getFrameId(name, pin.FrameType.BODY)]
        if frame.parentJoint == 0:
            continue
        for element in link.iter(kind):
            geometry = element.find("geometry")
            points = None if geometry is None else _points(geometry, urdf, packages)
            if points is None or not len(points):
                continue
            placement = frame.placement * _placement(element.find("origin"))
            out.setdefault(frame.parentJoint, []).append(
                points @ placement.rotation.T + placement.translation)
    return {j: np.vstack(p) for j, p in out.items()}


def urdf_body_points(entry, model: pin.Model) -> dict[int, tuple[str, np.ndarray]]:
    """Per joint of the arm's Pinocchio model (1-based) whose links in the registry entry's
    URDF carry any, which geometry ("collision", else "visual") and its points (body_points)."""
    from harness.robots.registry import erd_robots_dir

    packages = (erd_robots_dir().parent.parent,) if entry.source == "example-robot-data" else ()
    found: dict[int, tuple[str, np.ndarray]] = {}
    for kind in ("visual", "collision"):  # collision where a body has both
        found.update({j: (kind, p) for j, p in
                      body_points(Path(entry.urdf), model, packages, kind).items()})
    return found
