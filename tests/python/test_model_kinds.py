"""The builder's vocabulary comes from the library's table of model kinds (lsmbs.model_kinds(),
src/lsmbs/io/model_kinds.cpp), the one the case-file loader reads joints, forces, measures and
features with. References: the signatures the hand-written builder had (tests and users call
them), the case format's documentation, and the loader's own refusals."""
import inspect
import re

import pytest

import lsmbs
from lsmbs import at, ground

from conftest import ROOT

KINDS = lsmbs._lsmbs.model_kinds()


def test_every_joint_and_force_is_a_builder_method_and_every_feature_a_function():
    for k in KINDS:
        if k["section"] in ("joints", "forces"):
            method = getattr(lsmbs.ModelBuilder, k["type"])
            assert method.__doc__.startswith(k["doc"][0].upper()), k["type"]
            params = list(inspect.signature(method).parameters)
            assert params[:2] == ["self", "name"]
            assert set(params[2:]) == {key["name"] for key in k["keys"]}, k["type"]
        elif k["section"] == "features":
            assert callable(getattr(lsmbs, k["type"])), k["type"]


def test_the_signatures_are_those_users_call():
    # the hand-written builder's signatures, which the examples, docs and tests use
    expected = {
        "revolute": "(self, name, a, b=None)",
        "prismatic": "(self, name, a, direction, *, through=None, lock_rotation=None)",
        "rigid_connection": "(self, name, rigid, flexible, node_set)",
        "rotation_driver": "(self, name, body, law, relative_to=None)",
        "translation_driver": "(self, name, point, direction, law, through=None)",
        "point_force": "(self, name, point, force=None, *, fx=None, fy=None, scale=None)",
        "spring_damper": "(self, name, a, b, *, stiffness, damping=None, free_length=None)",
        "torque": "(self, name, body, torque=None, *, law=None, scale=None)",
        "rotational_spring_damper":
            "(self, name, a, b='ground', *, stiffness, damping=None, free_angle=None)",
        "pressure": "(self, name, point, direction, area, table, argument=None, time_offset=None)",
    }
    for name, sig in expected.items():
        assert str(inspect.signature(getattr(lsmbs.ModelBuilder, name))) == sig, name
    assert str(inspect.signature(lsmbs.ellipse)) == \
        "(name, cx, cy, a, b, d=1.0, angle=None, hole=True, *, non_design=None)"


def test_documents_are_written_as_the_case_format_has_them():
    m = lsmbs.ModelBuilder("doc")
    m.rigid_body("bob", position=(1, 0), mass=1, inertia=0.1)
    m.revolute("pin", at("bob", (-1, 0)))
    m.rotational_spring_damper("coil", "bob", stiffness=5)
    m.spring_damper("spring", at("bob"), ground((2, 0)), stiffness=3, free_length=0.5)
    d = m.document()
    assert d["joints"] == [{"name": "pin", "type": "revolute",
                            "a": {"body": "bob", "at": [-1.0, 0.0]}}]
    assert d["forces"][0] == {"name": "coil", "type": "rotational_spring_damper", "a": "bob",
                              "b": "ground", "stiffness": 5.0}
    assert d["forces"][1]["b"] == {"ground": [2.0, 0.0]} and d["forces"][1]["free_length"] == 0.5
    assert lsmbs.ellipse("h", 0.1, 0, 0.01, 0.02) == {
        "name": "h", "type": "ellipse", "hole": True, "cx": 0.1, "cy": 0.0, "a": 0.01, "b": 0.02,
        "d": 1.0}
    assert "hole" not in lsmbs.circle("ring", 0, 0, 0.01, non_design=True)


def test_wrong_calls_are_refused_at_the_call():
    m = lsmbs.ModelBuilder("wrong")
    m.rigid_body("bob", position=(1, 0), mass=1, inertia=0.1)
    with pytest.raises(TypeError, match="stiffness"):
        m.spring_damper("s", at("bob"), ground((0, 0)))  # a required keyword
    with pytest.raises(TypeError, match="unexpected keyword"):
        m.revolute("pin", at("bob"), bee=1)
    with pytest.raises(TypeError, match="expected a point"):
        m.revolute("pin", (0, 0))
    with pytest.raises(TypeError, match="has no key 'pont'; its keys: point"):
        m.measure("tip", "position", pont=at("bob"))
    with pytest.raises(TypeError, match="needs body="):
        m.measure("th", "angle")


def test_the_case_format_documents_every_kind_and_key():
    text = (ROOT / "docs" / "case-format.md").read_text()
    paragraphs = re.split(r"\n\s*\n", text)
    for k in KINDS:
        where = [p for p in paragraphs if f"`{k['type']}`" in p]
        assert where, f"docs/case-format.md does not name the {k['section']} kind {k['type']!r}"
        for key in k["keys"]:
            assert any(re.search(rf"\b{key['name']}\b", p) for p in where), \
                f"docs/case-format.md: the {k['type']} key {key['name']!r} is not described"
