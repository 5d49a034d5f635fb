"""The one place a robot's file is parsed: into MuJoCo and into Pinocchio, with one clear
error line for a file either cannot read. Only harness.robots.arm.Arm calls these (once per
model, lazily), but for the MJCF `export` writes (model_to_save) and reads back
(plain_mujoco, the rollout's); everything else asks an Arm.

A registered robot with an MJCF is compiled from it (its scene, the replay's, from its scene
file); any URDF keeps its arm joints only (grippers and fingers held fixed) and, for MuJoCo,
loses its meshes so `package://` paths need not resolve (inertias come from <inertial>).
"""

from __future__ import annotations

import os
import re
import sys
import tempfile
import xml.etree.ElementTree as ET
from contextlib import contextmanager
from pathlib import Path

import mujoco
import pinocchio as pin

from harness.errors import UserError
from harness.robots.registry import Robot
from harness.robots.subchain import hold_outside_chain
from harness.robots.urdf import arm_urdf, repair_inertias, strip_geometry

# What Pinocchio's bindings raise on a description they cannot map (boost.python's
# translation of std::invalid_argument, runtime_error, out_of_range, overflow_error).
PINOCCHIO_ERRORS = (ValueError, RuntimeError, IndexError, OverflowError)


@contextmanager
def native_output(lines: list[str]):
    """Collect what C/C++ parsers print on file descriptors 1 and 2 (urdfdom's parse errors,
    TinyXML's warnings) into lines instead of the user's terminal; the caller decides."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 1)
        os.dup2(tmp.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            tmp.seek(0)
            lines += [x.strip() for x in tmp.read().decode(errors="replace").splitlines()
                      if x.strip()]


def _parse(build, path: Path, problem: str):
    """build() under native_output: its printout is re-issued as one warning line on success
    and becomes the detail of the UserError on failure."""
    printed: list[str] = []
    try:
        with native_output(printed):
            model = build()
    except (mujoco.FatalError, *PINOCCHIO_ERRORS) as exc:
        detail = " ".join(str(exc).split()) or "; ".join(printed[:2]) or "parse error"
        raise UserError(f"{problem}: {detail}") from None
    # urdfdom reports an element it could not parse, and goes on without it; MuJoCo warns of a
    # NaN in the file and builds a model with it
    errors = [line for line in printed
              if line.lower().startswith("error") or "contains a 'nan'" in line.lower()]
    if errors:
        raise UserError(f"{problem}: {'; '.join(' '.join(e.split()) for e in errors[:2])}")
    if printed:
        print(f"torquebench: warning: {path}: {'; '.join(printed[:3])}", file=sys.stderr)
    return model


def read_text(path: Path) -> str:
    """A robot description's text; UserError if it is not readable UTF-8 text."""
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise UserError(f"robot file {path} is not UTF-8 text") from None
    except OSError as exc:
        raise UserError(f"cannot read robot file {path}: {exc.strerror}") from None


def arm_urdf_text(entry: Robot) -> str:
    """The entry's URDF with its arm joints only (the others fixed)."""
    return arm_urdf(read_text(entry.urdf), str(entry.urdf) if entry.chain else entry.name,
                    entry.chain, entry.hold)


def chain_record(entry: Robot) -> dict:
    """What Arm.record keeps of the entry's chain: 'chain' (BASE:TIP), 'held' (the joints it
    holds fixed: harness.robots.subchain.hold_outside_chain's joint, type, position) and the
    positions --hold stated ('hold', as given); {} without a chain."""
    if entry.chain is None:
        return {}
    held = hold_outside_chain(ET.fromstring(read_text(entry.urdf)), *entry.chain,
                              str(entry.urdf), entry.hold)
    record = {"chain": ":".join(entry.chain), "held": held}
    return {**record, "hold": dict(entry.hold)} if entry.hold else record


def inertia_repairs(entry: Robot) -> list[dict]:
    """The link inertias of the entry's URDF repaired for MuJoCo (harness.robots.urdf.
    repair_inertias): which link, before and after; none for an MJCF."""
    if entry.urdf is None:
        return []
    try:
        return repair_inertias(ET.fromstring(read_text(entry.urdf)))
    except ET.ParseError:  # reported where the file is parsed
        return []


def parse_spec(entry: Robot, scene: bool = False) -> mujoco.MjSpec:
    """The entry's MuJoCo spec, the one MuJoCo parse of its file: its MJCF (scene: its scene
    MJCF, if it has one), else its URDF's arm without meshes."""
    if entry.mjcf is not None:
        path = entry.scene if scene and entry.scene is not None else entry.mjcf
        return _parse(lambda: mjcf_spec(path), path, f"invalid MJCF {path}")
    text = strip_geometry(arm_urdf_text(entry))
    return _parse(lambda: mujoco.MjSpec.from_string(text), entry.urdf, f"invalid URDF {entry.urdf}")


def compile_spec(spec: mujoco.MjSpec, entry: Robot) -> mujoco.MjModel:
    """A copy of spec compiled (the spec stays as parsed); UserError naming the file."""
    path = entry.mjcf or entry.urdf
    return _parse(lambda: spec.copy().compile(), path, f"invalid robot file {path}")


def mjcf_spec(path: Path) -> mujoco.MjSpec:
    """The spec of the MJCF at path whatever its suffix, its includes and assets found beside
    it, as MjModel.from_xml_path reads it (MjSpec.from_file picks a decoder by the suffix:
    an exported `.mjcf` had none)."""
    if path.suffix.lower() == ".xml":
        return mujoco.MjSpec.from_file(str(path))
    includes: dict[str, bytes] = {}
    pending = [read_text(path)]
    while pending:
        for name in re.findall(r'<include\b[^>]*\bfile="([^"]+)"', pending.pop()):
            if name not in includes:
                includes[name] = (path.parent / name).read_bytes()
                pending.append(includes[name].decode(errors="replace"))
    spec = mujoco.MjSpec.from_string(read_text(path), include=includes)
    spec.modelfiledir = str(path.parent.resolve()) + "/"
    return spec


def model_to_save(entry: Robot) -> mujoco.MjModel:
    """The entry's MuJoCo model parsed again, for `export --format mjcf` alone: MuJoCo saves a
    model through the XML it parsed last (mj_saveLastXML; it and MjSpec.to_xml keep 6 digits,
    harness.robots.export rewrites the inertials at full precision), so the model to change and
    save must be the last one parsed from XML."""
    if entry.mjcf is not None:
        return _parse(lambda: mujoco.MjModel.from_xml_path(str(entry.mjcf)), entry.mjcf,
                      f"invalid MJCF {entry.mjcf}")
    text = strip_geometry(arm_urdf_text(entry))
    return _parse(lambda: mujoco.MjModel.from_xml_string(text), entry.urdf,
                  f"invalid URDF {entry.urdf}")


def plain_mujoco(path: Path) -> mujoco.MjModel:
    """The MJCF at path as plain MuJoCo reads it (MjModel.from_xml_path, no spec of this
    project's): a file `export --format mjcf` wrote, read back as its user would."""
    return _parse(lambda: mujoco.MjModel.from_xml_path(str(path)), path, f"invalid MJCF {path}")


def parse_pinocchio(entry: Robot) -> pin.Model:
    """The entry's Pinocchio model: from its URDF (arm joints only), else from its MJCF."""
    if entry.urdf is not None:
        text = arm_urdf_text(entry)
        return _parse(lambda: pin.buildModelFromXML(text), entry.urdf,
                      f"Pinocchio cannot read {entry.urdf}")
    return _parse(lambda: pin.buildModelFromMJCF(str(entry.mjcf)), entry.mjcf,
                  f"Pinocchio cannot read {entry.mjcf}")
