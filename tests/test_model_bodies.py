"""MODEL.json a person can read: a consistent fit names each body's parameters with units and
the URDF's value beside, its joints' dynamics, and what each base atom sums; metrics unchanged."""

from __future__ import annotations

import json

import pytest

from harness.cli import main

pytestmark = pytest.mark.slow  # two identifications of a UR5 log


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    d = tmp_path_factory.mktemp("bodies")
    assert main(["generate", "--robot", "ur5", "--samples", "1500", "--noise", "0.01",
                 "--seed", "3", "--out", str(d / "ur5.npz")]) == 0
    for prior in ("nominal", "none"):
        assert main(["identify", "--data", str(d / "ur5.npz"), "--robot", "ur5", "--prior",
                     prior, "--out", str(d / f"{prior}.json")]) == 0
    return d


def test_model_json_names_bodies_and_base_parameters(fitted):
    payload = json.loads((fitted / "nominal.json").read_text())
    body = payload["bodies"][1]
    assert body["mass"]["unit"] == "kg" and body["consistent"] is True
    assert abs(body["mass"]["value"] - body["mass"]["nominal"]) < 0.1 * body["mass"]["nominal"]
    assert set(payload["joints_dynamics"][0]) == {"joint", "armature", "viscous", "coulomb"}
    assert "nominal" not in payload["metrics"]["physical"]  # metrics stay as they were
    # plausible by default: each body inside the ellipsoid of its link's collision meshes
    assert all(b["plausible"] for b in payload["bodies"])
    assert all("collision geometry" in b["ellipsoid"]["source"] for b in payload["bodies"])
    assert payload["metrics"]["physical"]["plausible"] == [True] * 6
    sparse = json.loads((fitted / "none.json").read_text())
    assert "bodies" not in sparse
    assert set(sparse["base_parameters"]) == {"explanation", *sparse["atoms"]}
