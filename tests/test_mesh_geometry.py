"""Meshes the harness reads and those it cannot (issue #58): a link meshed in .obj or .dae
gets a capsule of its mesh (not a centre line), and a link whose mesh is missing or of an
unknown format is named once on stderr and in Arm.unread_geometry, never dropped silently."""

from __future__ import annotations

import json

import numpy as np
import pytest

from harness.cli import main
from harness.robots.arm import Arm
from harness.robots.collision import read_mesh

LINK = """<link name="{name}"><inertial><mass value="1"/>
<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><origin xyz="0 0 0.15"/><geometry><mesh filename="{mesh}" scale="{scale}"/></geometry>
</collision></link>"""
ARM = """<robot name="r"><link name="base"/>{l1}{l2}<link name="tip"/>
<joint name="tip" type="fixed"><parent link="l2"/><child link="tip"/><origin xyz="0 0 0.2"/></joint>
<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 1 0"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.3"/>
<axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"""
CUBE_DAE = """<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<asset><unit name="millimetre" meter="0.001"/><up_axis>Z_UP</up_axis></asset>
<library_geometries><geometry id="cube" name="cube"><mesh>
<source id="cube-positions"><float_array id="cube-positions-array" count="24">{coords}</float_array>
<technique_common><accessor source="#cube-positions-array" count="8" stride="3">
<param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
</accessor></technique_common></source>
<vertices id="cube-vertices"><input semantic="POSITION" source="#cube-positions"/></vertices>
<triangles count="12"><input semantic="VERTEX" source="#cube-vertices" offset="0"/>
<p>{faces}</p></triangles></mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="Scene" name="Scene"><node id="cube" name="cube">
<instance_geometry url="#cube"/></node></visual_scene></library_visual_scenes>
<scene><instance_visual_scene url="#Scene"/></scene></COLLADA>"""
CORNERS = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
FACES = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
         (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]


def _cube_obj(path, half: float) -> None:
    """A cube of half-side half (file units) in Wavefront OBJ."""
    lines = [f"v {half * x} {half * y} {half * z}" for x, y, z in CORNERS]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in FACES]
    path.write_text("\n".join(lines) + "\n")


def _arm(tmp_path, first: str, second: str, scale: str = "1 1 1") -> Arm:
    path = tmp_path / "arm.urdf"
    path.write_text(ARM.format(l1=LINK.format(name="l1", mesh=first, scale=scale),
                               l2=LINK.format(name="l2", mesh=second, scale=scale)))
    return Arm.of(path)


def test_obj_meshes_give_capsules_and_a_missing_dae_is_named_once(tmp_path, capsys):
    _cube_obj(tmp_path / "cube.obj", 0.04)
    arm = _arm(tmp_path, "cube.obj", "meshes/missing.dae")
    geometry = arm.capsules()
    assert len(geometry.radii) == 2
    assert geometry.radii[0] > 0.03  # holds the cube of half-side 0.04 m, not a centre line
    assert geometry.radii[1] == 0  # nothing read: the centre line (and the warning below)
    assert [(u.link, u.file) for u in arm.unread_geometry] == [("l2", "meshes/missing.dae")]
    assert "not found" in arm.unread_geometry[0].reason
    _ = arm.capsules(0.01), arm.ellipsoids  # read once: no second warning
    err = capsys.readouterr().err
    assert err.count("warning") == 1, err
    assert "link l2" in err and "meshes/missing.dae" in err and "l1" not in err


def test_an_unknown_format_is_named_with_its_reason(tmp_path, capsys):
    (tmp_path / "part.3ds").write_bytes(b"\0" * 64)
    _cube_obj(tmp_path / "cube.obj", 0.04)
    arm = _arm(tmp_path, "cube.obj", "part.3ds")
    assert [u.link for u in arm.unread_geometry] == ["l2"]
    assert "format .3ds" in arm.unread_geometry[0].reason
    assert "part.3ds" in capsys.readouterr().err


def test_a_dae_mesh_is_read_in_metres_by_its_unit(tmp_path, capsys):
    coords = " ".join(f"{40 * c}" for corner in CORNERS for c in corner)  # 40 mm half-side
    faces = " ".join(str(i) for face in FACES for i in face)
    (tmp_path / "cube.dae").write_text(CUBE_DAE.format(coords=coords, faces=faces))
    vertices = read_mesh(tmp_path / "cube.dae")
    assert np.allclose(np.abs(vertices), 0.04)
    _cube_obj(tmp_path / "cube.obj", 0.04)
    arm = _arm(tmp_path, "cube.dae", "cube.obj")
    assert arm.unread_geometry == ()
    radii = arm.capsules().radii
    assert radii[0] == pytest.approx(radii[1], rel=1e-3) and radii[0] > 0.03
    assert capsys.readouterr().err == ""


def test_replay_json_names_the_unread_geometry(tmp_path, capsys):
    _cube_obj(tmp_path / "cube.obj", 0.04)
    _arm(tmp_path, "cube.obj", "meshes/missing.dae")
    t = np.linspace(0.0, 1.0, 50)
    still = np.zeros((len(t), 2)).tolist()
    plan = {"t": t.tolist(), "q": still, "qd": still, "qdd": still,
            "obstacle": [[1.0, 1.0, 1.0]] * len(t), "threshold": 0.05}
    (tmp_path / "plan.json").write_text(json.dumps(plan))
    out = tmp_path / "replay.json"
    assert main(["replay", "--plan", str(tmp_path / "plan.json"), "--robot",
                 str(tmp_path / "arm.urdf"), "--out", str(out)]) == 0
    unread = json.loads(out.read_text())["unread_geometry"]
    assert [(u["link"], u["file"]) for u in unread] == [("l2", "meshes/missing.dae")]
    assert "not found" in unread[0]["reason"]


def test_plan_json_names_the_unread_geometry(tmp_path, capsys):
    _cube_obj(tmp_path / "cube.obj", 0.04)
    _arm(tmp_path, "cube.obj", "meshes/missing.dae")
    out = tmp_path / "plan.json"
    assert main(["plan", "--no-compile", "--model", "pinocchio", "--robot",
                 str(tmp_path / "arm.urdf"), "--start", "0.2,0.1", "--goal", "1.0,-0.5",
                 "--obstacle-from", "0.3,0.3,0.5", "--obstacle-to", "0.3,0.3,0.9",
                 "--torque-limit", "none", "--out", str(out)]) == 0
    unread = json.loads(out.read_text())["unread_geometry"]
    assert [(u["link"], u["file"]) for u in unread] == [("l2", "meshes/missing.dae")]


def test_package_meshes_resolve_as_ros_resolves_them(tmp_path, monkeypatch, capsys):
    """`package://NAME/...` found under ROS_PACKAGE_PATH's folders, and an example-robot-data
    URDF copied out of the wheel still finds its meshes (the UR10 copied as a new user does
    lost all six links' geometry, read from the wheel when not copied)."""
    import shutil

    from harness.robots.registry import erd_robots_dir

    _cube_obj(tmp_path / "cube.obj", 0.04)
    package = tmp_path / "ros" / "my_arm" / "meshes"
    package.mkdir(parents=True)
    shutil.copy(tmp_path / "cube.obj", package / "link.obj")
    folder = tmp_path / "elsewhere"
    folder.mkdir()
    mesh = "package://my_arm/meshes/link.obj"
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "nowhere") + ":" + str(tmp_path / "ros"))
    arm = _arm(folder, mesh, mesh)
    assert arm.capsules().radii[0] > 0.03 and not arm.unread_geometry
    monkeypatch.delenv("ROS_PACKAGE_PATH")
    (tmp_path / "again").mkdir()
    assert [u.link for u in _arm(tmp_path / "again", mesh, mesh).unread_geometry] == \
        ["l1", "l2"]  # the same URDF with nowhere to look
    capsys.readouterr()
    copied = tmp_path / "ur10.urdf"
    shutil.copy(erd_robots_dir() / "ur_description" / "urdf" / "ur10_robot.urdf", copied)
    ur10 = Arm.of(copied)
    assert not ur10.unread_geometry and min(ur10.capsules().radii) > 0
    assert "warning" not in capsys.readouterr().err
