"""A robot's collision (or visual) geometry as points: what the link capsules
(harness.robots.capsules) and the bodies' ellipsoids (harness.robots.ellipsoids) are fitted to.

Each body's URDF <collision> (or <visual>) elements: meshes (STL, OBJ, COLLADA .dae, PLY;
all but STL read with trimesh, a .dae scaled by its <unit meter>), boxes, cylinders,
spheres, at q = 0, bodies fixed to it included. A body without geometry (none, an MJCF) has
no points. Geometry the harness cannot read (a missing file, another format, a broken file)
is not skipped silently: urdf_geometry names each such (link, file, reason), and the Arm
warns of them once (Arm.unread_geometry).
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from importlib import metadata
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pinocchio as pin

SPHERE_DIRECTIONS = 26  # points on a sphere or cylinder rim standing for its surface
MESH_FORMATS = (".stl", ".obj", ".dae", ".ply")  # the mesh files read (read_mesh)


class UnreadMesh(ValueError):
    """A mesh the harness cannot read; its message is the reason."""


class UnreadGeometry(NamedTuple):
    """A link's geometry element the harness could not read: the link, the file the URDF
    names (as written there; the element's tag if it names none) and why."""

    link: str
    file: str
    reason: str


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


def _collada_unit(path: Path) -> float:
    """The metres per unit a COLLADA file's <asset><unit meter=...> declares (1 if none)."""
    head = path.read_bytes()[:8192].decode(errors="replace")
    found = re.search(r"<unit\b[^>]*\bmeter\s*=\s*[\"']([^\"']+)", head)
    return float(found.group(1)) if found else 1.0


def read_mesh(path: Path) -> np.ndarray:
    """Vertices (n, 3) of a mesh file of MESH_FORMATS, in metres for a .dae (its unit), in the
    file's units otherwise; UnreadMesh (its reason) for another format, a broken file or one
    without vertices."""
    suffix = path.suffix.lower()
    if suffix not in MESH_FORMATS:
        raise UnreadMesh(f"mesh format {suffix or '(none)'} is not read "
                         f"(only {', '.join(MESH_FORMATS)})")
    try:
        if suffix == ".stl":
            vertices = read_stl(path)
        else:
            import trimesh

            mesh = trimesh.load(path, force="mesh", process=False)
            vertices = np.asarray(getattr(mesh, "vertices", ()), float).reshape(-1, 3)
            if suffix == ".dae":
                vertices = vertices * _collada_unit(path)
    except Exception as exc:  # noqa: BLE001 - a broken file of any kind: its reason
        raise UnreadMesh(f"cannot be read ({type(exc).__name__}: {exc})") from None
    if not len(vertices) or not np.all(np.isfinite(vertices)):
        raise UnreadMesh("no (finite) vertices in it")
    return vertices


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


def _points(shape: ET.Element, urdf: Path, packages: tuple[Path, ...]) -> np.ndarray:
    """Points (n, 3) in the collision element's frame standing for its surface; UnreadMesh
    (its reason) for a mesh not found or not read or a shape of no known kind, ValueError,
    TypeError or AttributeError for a shape's bad attributes."""
    if shape.tag == "mesh":
        path = _resolve(shape.get("filename", ""), urdf, packages)
        if path is None:
            raise UnreadMesh("file not found")
        scale = np.array([float(v) for v in shape.get("scale", "1 1 1").split()])
        return read_mesh(path) * scale
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
    raise UnreadMesh(f"shape <{shape.tag}> is not read")


def _placement(element: ET.Element | None) -> pin.SE3:
    if element is None:
        return pin.SE3.Identity()
    xyz = np.array([float(v) for v in element.get("xyz", "0 0 0").split()])
    rpy = [float(v) for v in element.get("rpy", "0 0 0").split()]
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), xyz)


def body_points(urdf: Path, model: pin.Model, packages: tuple[Path, ...] = (),
                kind: str = "collision", joints: set[int] | None = None
                ) -> tuple[dict[int, np.ndarray], dict[int, list[UnreadGeometry]]]:
    """Per joint of model (1-based; of joints only if given) carrying any, the points (n, 3)
    standing for the surface of the URDF's `kind` ("collision" or "visual") geometry of the
    links it carries (links fixed to it included), in that joint's frame (m); and per joint,
    the elements of that kind that could not be read."""
    out: dict[int, list[np.ndarray]] = {}
    unread: dict[int, list[UnreadGeometry]] = {}
    for link in ET.parse(urdf).getroot().iter("link"):
        name = link.get("name")
        if not model.existFrame(name, pin.FrameType.BODY):
            continue
        frame = model.frames[model.getFrameId(name, pin.FrameType.BODY)]
        if frame.parentJoint == 0 or (joints is not None and frame.parentJoint not in joints):
            continue
        for element in link.iter(kind):
            geometry = element.find("geometry")
            shape = None if geometry is None else next(iter(geometry), None)
            if shape is None:
                continue  # no shape: nothing to read
            try:
                points = _points(shape, urdf, packages)
            except (UnreadMesh, ValueError, TypeError, AttributeError) as exc:
                reason = str(exc) if isinstance(exc, UnreadMesh) else f"bad <{shape.tag}> ({exc})"
                unread.setdefault(frame.parentJoint, []).append(
                    UnreadGeometry(name, shape.get("filename") or f"<{shape.tag}>", reason))
                continue
            placement = frame.placement * _placement(element.find("origin"))
            out.setdefault(frame.parentJoint, []).append(
                points @ placement.rotation.T + placement.translation)
    return {j: np.vstack(p) for j, p in out.items()}, unread


def urdf_geometry(entry, model: pin.Model
                  ) -> tuple[dict[int, tuple[str, np.ndarray]], tuple[UnreadGeometry, ...]]:
    """Per joint of the arm's Pinocchio model (1-based) whose links in the registry entry's
    URDF carry any, which geometry ("collision", else "visual") and its points (body_points);
    and the geometry that could not be read where it counts: of the kind a joint's points
    are of, or of either kind on a joint left without points."""
    packages = package_roots()
    urdf = Path(entry.urdf)
    collision, missed = body_points(urdf, model, packages, "collision")
    rest = set(range(1, model.njoints)) - set(collision)
    visual, missed_visual = body_points(urdf, model, packages, "visual", rest)
    found = {**{j: ("visual", p) for j, p in visual.items()},
             **{j: ("collision", p) for j, p in collision.items()}}
    unread = [u for j in sorted(set(missed) | set(missed_visual))
              for u in (missed.get(j, []) if j in collision else
                        missed_visual.get(j, []) if j in visual else
                        missed.get(j, []) + missed_visual.get(j, []))]
    return found, tuple(unread)


def package_roots() -> tuple[Path, ...]:
    """Where `package://NAME/...` is looked for, as ROS looks: each folder of
    ROS_PACKAGE_PATH, each prefix's share/ of AMENT_PREFIX_PATH, and the share/ folder of the
    example-robot-data wheel (a URDF copied out of it still finds its meshes); the URDF's own
    folders are tried after these (_resolve)."""
    from harness.errors import UserError
    from harness.robots.registry import erd_robots_dir

    roots = [Path(p) for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    roots += [Path(p) / "share" for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep)
              if p]
    try:
        roots.append(erd_robots_dir().parent.parent)
    except (UserError, metadata.PackageNotFoundError):
        pass
    return tuple(roots)


def urdf_body_points(entry, model: pin.Model) -> dict[int, tuple[str, np.ndarray]]:
    """urdf_geometry's points alone."""
    return urdf_geometry(entry, model)[0]
