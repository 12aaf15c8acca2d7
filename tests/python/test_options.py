"""The core's options structs as Python classes: bound once, documented from the headers, taken
by the wrappers as an object or as keywords, and safe to copy and send to workers."""

from __future__ import annotations

import copy
import math
import pickle
import re
from pathlib import Path

import numpy as np
import pytest
from simplify_inputs import bending_tube

from animlod import _core, options, simplify_animated
from animlod.aqem import check_aqem_options
from animlod.options import AqemOptions, MotionFeatureOptions, MotionRefitOptions, TdagOptions

HEADERS = Path(__file__).resolve().parents[2] / "cpp" / "include" / "animlod"
OPTION_CLASSES = [getattr(options, name) for name in options.__all__ if name.endswith("Options")]


def test_every_options_struct_of_the_headers_is_bound():
    declared = r"^struct (\w+Options) \{"
    structs = {name for header in HEADERS.glob("*.hpp") for name in re.findall(declared, header.read_text(), re.M)}
    assert structs == {cls.__name__ for cls in OPTION_CLASSES}


@pytest.mark.parametrize("cls", OPTION_CLASSES, ids=lambda cls: cls.__name__)
def test_every_field_carries_its_header_comment(cls):
    assert cls.__doc__ and cls.fields
    for name in cls.fields:
        assert getattr(cls, name).__doc__.strip(), f"{cls.__name__}.{name} has no docstring"


def test_defaults_are_the_structs():
    aqem = AqemOptions()
    assert aqem.target_ratios == (0.5,) and math.isinf(aqem.max_error) and aqem.placement == "optimal"
    assert aqem.motion_features.min_angle_change == pytest.approx(math.radians(1.0))
    assert TdagOptions().governing == "first" and MotionRefitOptions().chunk_frames == 64
    mesh = bending_tube(frames=4)
    implicit = simplify_animated(mesh)
    explicit = simplify_animated(mesh, options=AqemOptions())
    np.testing.assert_array_equal(implicit.levels[0].mesh.faces, explicit.levels[0].mesh.faces)


def test_keywords_reach_nested_options_and_bad_ones_are_named():
    made = AqemOptions(max_error=0.5, noise_mads=3.0, feature_weighting="paper")
    assert made.max_error == 0.5 and made.motion_features.noise_mads == 3.0
    assert made.motion_features.feature_weighting == "paper"
    with pytest.raises(ValueError, match=r"^AqemOptions: unknown option 'max_eror' \(options: target_ratios, "):
        AqemOptions(max_eror=1.0)
    with pytest.raises(ValueError, match=r"^AqemOptions.max_frames: expected an integer >= 0, got -3$"):
        AqemOptions(max_frames=-3)
    with pytest.raises(ValueError, match=r"^AqemOptions.target_ratios: expected a list of numbers, got \['a'\]$"):
        AqemOptions(target_ratios=["a"])
    with pytest.raises(ValueError, match=r"^AqemOptions.placement: expected one of 'optimal', 'on_edge', got 'edge'$"):
        AqemOptions(placement="edge")
    with pytest.raises(ValueError, match=r"^LodSelectorOptions.hysteresis: must be >= 0, got -0.5$"):
        _core.LodSelectorOptions().hysteresis = -0.5


@pytest.mark.parametrize(
    "ratios, fields, message",
    [
        ((1.5,), {}, r"^target_ratios: 1\.500000 outside \(0, 1\]$"),
        ((), {}, r"^target_ratios: no level requested$"),
        (None, {"max_error": -1.0}, r"^max_error: must be >= 0$"),
        (None, {"target_face_counts": [3, 0]}, r"^target_face_counts: 0 outside \[1, M\]"),
        (None, {"frame_subset": [-1]}, r"^frame_subset: frame -1 is negative$"),
        (None, {"noise_mads": -1.0}, r"^motion features: noise_mads must be finite and >= 0$"),
        (None, {"placement": "middle"}, r"^AqemOptions\.placement: expected one of"),
    ],
)
def test_aqem_options_are_checked_without_a_mesh_as_simplify_refuses_them(ratios, fields, message):
    with pytest.raises(ValueError, match=message):
        check_aqem_options(ratios, **fields)
    with pytest.raises(ValueError, match=message):
        simplify_animated(bending_tube(frames=2), ratios, **fields)


def test_aqem_options_a_mesh_decides_pass_the_check_without_one():
    check_aqem_options((0.5, 1.0), target_face_counts=[10**9], frame_subset=[10**6], max_error=0.0)
    check_aqem_options(noise_mads=-1.0, use_motion_features=False)


def test_copies_are_deep_and_pickles_round_trip():
    original = AqemOptions(max_error=0.25, feature_weighting="paper", frame_subset=[0, 2])
    for other in (copy.copy(original), copy.deepcopy(original), pickle.loads(pickle.dumps(original))):
        assert other == original and other is not original
        other.motion_features.noise_mads = 1.0
        assert original.motion_features.noise_mads == MotionFeatureOptions().noise_mads
    assert AqemOptions() != original
    assert repr(original).startswith("AqemOptions(target_ratios=(0.5,), target_face_counts=(), max_error=0.25,")


def test_wrappers_take_an_object_and_keywords_without_changing_the_object():
    mesh = bending_tube(frames=4)
    coarse = AqemOptions(use_motion_features=False, target_ratios=[0.1])
    both = simplify_animated(mesh, None, coarse, placement="on_edge")
    assert coarse.placement == "optimal" and coarse.target_ratios == (0.1,)
    keywords = simplify_animated(mesh, (0.1,), use_motion_features=False, placement="on_edge")
    np.testing.assert_array_equal(both.levels[0].mesh.frames, keywords.levels[0].mesh.frames)
    with pytest.raises(ValueError, match=r"^options: expected AqemOptions, got dict$"):
        simplify_animated(mesh, None, {"max_error": 1.0})


def test_the_installed_stub_lists_what_the_module_binds():
    stub = Path(_core.__file__).with_name("_core.pyi")
    if not stub.exists():
        pytest.skip("built without ANIMLOD_PYTHON_STUB (make sanitize)")
    text = stub.read_text()
    listed = re.search(r"^__all__: list\[str\] = \[(.*)\]$", text, re.M).group(1)
    assert set(listed.replace("'", "").split(", ")) == {name for name in dir(_core) if not name.startswith("_")}
    assert "def simplify_animated(" in text and "class AqemOptions:" in text


LIST_FIELDS = [("target_ratios", [0.5, 0.25]), ("target_face_counts", [40, 20]), ("frame_subset", [0, 3])]


@pytest.mark.parametrize("name, values", LIST_FIELDS)
def test_list_fields_read_as_tuples_so_an_append_fails_instead_of_doing_nothing(name, values):
    made = AqemOptions()
    with pytest.raises(AttributeError, match="'tuple' object has no attribute 'append'"):
        getattr(made, name).append(values[0])  # a list copy took it and the field stayed as it was
    setattr(made, name, values)
    assert getattr(made, name) == tuple(values)
    setattr(made, name, getattr(made, name) + (values[-1],))
    assert getattr(made, name) == tuple(values) + (values[-1],)
    assert AqemOptions(**{name: values}) == pickle.loads(pickle.dumps(AqemOptions(**{name: tuple(values)})))
    assert "Read as a tuple" in getattr(AqemOptions, name).__doc__


def test_only_list_fields_read_as_tuples():
    listed = {
        (cls.__name__, name) for cls in OPTION_CLASSES for name in cls.fields if isinstance(getattr(cls(), name), tuple)
    }
    assert listed == {("AqemOptions", name) for name, _ in LIST_FIELDS}
