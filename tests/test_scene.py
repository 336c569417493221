"""Scenes: the shipped files load, dimensions follow the effects, bad files name the field."""

import copy
import json
import re
import warnings

import numpy as np
import pytest

from clsamp.errors import InvalidArgumentError
from clsamp.scene import EFFECTS, Scene, shipped_scenes
from clsamp.tour import TOUR_RENDER_SAMPLERS

BASE = {
    "name": "t",
    "camera": {"eye": [0, 2, 5], "look_at": [0, 0, 0], "fov": 40,
               "lens": {"aperture": 0.1, "focus_distance": 5}, "shutter": [0, 1]},
    "shapes": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0]},
               {"type": "sphere", "center": [0, 1, 0], "radius": 1, "velocity": [1, 0, 0]},
               {"type": "box", "min": [1, 0, 0], "max": [2, 1, 1]}],
    "light": {"corner": [-1, 4, -1], "edge1": [2, 0, 0], "edge2": [0, 0, 2], "emission": 5},
    "ambient_occlusion": {"rays": 3, "distance": 2},
    "effects": [],
}


def with_(effects=None, **changes):
    data = copy.deepcopy(BASE)
    if effects is not None:
        data["effects"] = effects
    data.update(changes)
    return data


def test_shipped_scenes_load_and_ao_is_the_tour_scene():
    assert {"ao", "dof", "motion_blur", "soft_shadows", "combined"} <= set(shipped_scenes())
    ao = Scene.from_file("ao")
    assert ao.name == "ao" and ao.description and ao.default_spp == 128
    assert ao.effects == ("ambient_occlusion",) and ao.ao_rays == 1 and ao.sample_dimensions == 2
    combined = Scene.from_file("combined")
    assert combined.effects == EFFECTS and combined.sample_dimensions == 2 + 2 + 1 + 2 + 2


def test_a_path_works_as_well_as_a_name(tmp_path):
    path = tmp_path / "mine.json"
    path.write_text(json.dumps(with_(["antialiasing"], name="mine")))
    scene = Scene.from_file(path)
    assert scene.name == "mine" and scene.effects == ("antialiasing",)
    assert Scene.from_file(str(path)).to_dict() == scene.to_dict()


def test_each_effect_adds_its_dimensions_in_the_fixed_order():
    assert Scene.from_dict(with_([])).sample_dimensions == 0
    assert Scene.from_dict(with_(["antialiasing"])).sample_dimensions == 2
    assert Scene.from_dict(with_(["antialiasing", "depth_of_field"])).sample_dimensions == 4
    assert Scene.from_dict(with_(["antialiasing", "motion_blur"])).sample_dimensions == 3
    assert Scene.from_dict(with_(["ambient_occlusion"])).sample_dimensions == 6   # 3 AO rays
    assert Scene.from_dict(with_(["soft_shadows"])).sample_dimensions == 2
    # the order is fixed whatever order the file lists them in
    scene = Scene.from_dict(with_(["soft_shadows", "motion_blur", "antialiasing", "depth_of_field",
                                   "ambient_occlusion"]))
    assert [g for g, _ in scene.sample_groups] == ["pixel", "lens", "time", "ao0", "ao1", "ao2", "light"]
    assert scene.sample_dimensions == 2 + 2 + 1 + 6 + 2


def test_kernel_options_name_only_the_listed_effects():
    defines = Scene.from_dict(with_(["antialiasing"])).kernel_defines()
    on = {k for k, v in defines.items() if v}
    assert on == {"EFFECT_AA", "HAS_LIGHT"}
    defines = Scene.from_dict(with_(["depth_of_field", "ambient_occlusion"])).kernel_defines()
    assert defines["EFFECT_DOF"] and defines["AO_RAYS"] == 3 and not defines["EFFECT_MB"]


def test_content_hash_follows_the_content_not_the_name():
    a = Scene.from_dict(with_(["antialiasing"]))
    b = Scene.from_dict(with_(["antialiasing"], name="other", description="words"))
    c = Scene.from_dict(with_(["antialiasing"], background=0.5))
    assert a.content_hash() == b.content_hash() != c.content_hash()


@pytest.mark.parametrize("data, field", [
    (with_(["antialiasing", "bloom"]), "effects[1]"),
    (with_(["antialiasing", "antialiasing"]), "effects"),
    (with_(shapes=[{"type": "sphere", "center": [0, 0, 0], "radius": -1}]), "shapes[0].radius"),
    (with_(shapes=[{"type": "sphere", "center": [0, 0], "radius": 1}]), "shapes[0].center"),
    (with_(shapes=[{"type": "sphere", "center": [0, 0, 0], "raduis": 1}]), "shapes[0].raduis"),
    (with_(shapes=[{"type": "cone"}]), "shapes[0].type"),
    (with_(shapes=[{"type": "box", "min": [0, 0, 0], "max": [1, 0, 1]}]), "shapes[0].max"),
    (with_(shapes=[{"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 0]}]), "shapes[0].normal"),
    (with_(camera={"eye": [0, 0, 0], "look_at": [0, 0, 0]}), "camera.look_at"),
    (with_(camera={"look_at": [0, 0, 0]}), "camera.eye"),
    (with_(camera={"eye": [0, 1, 5], "look_at": [0, 0, 0], "fov": 0}), "camera.fov"),
    (with_(camera={"eye": [0, 1, 5], "look_at": [0, 0, 0], "shutter": [1, 0]}), "camera.shutter"),
    (with_(["depth_of_field"], camera={"eye": [0, 1, 5], "look_at": [0, 0, 0]}), "camera.lens"),
    (with_(["soft_shadows"], light=None), "light"),
    (with_(light={"corner": [0, 4, 0], "edge1": [1, 0, 0], "edge2": [2, 0, 0], "emission": 1}),
     "light.edge2"),
    (with_(ambient_occlusion={"rays": 0}), "ambient_occlusion.rays"),
    (with_(ambient_occlusion={"distance": -1}), "ambient_occlusion.distance"),
    (with_(default_spp=0), "default_spp"),
    (with_(background="white"), "background"),
])
def test_malformed_scenes_name_the_field(data, field):
    with pytest.raises(InvalidArgumentError, match=f"'{field}'".replace("[", r"\[").replace("]", r"\]")):
        Scene.from_dict(data)


def test_bad_files_say_where(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"camera": {"eye": [0, 1, 2],}')
    with pytest.raises(InvalidArgumentError, match="bad.json.*not valid JSON.*line 1"):
        Scene.from_file(bad)
    with pytest.raises(InvalidArgumentError, match="neither a scene file nor a shipped scene"):
        Scene.from_file("no_such_scene")
    with pytest.raises(ValueError):          # InvalidArgumentError is a ValueError too
        Scene.from_dict([1, 2])


@pytest.mark.parametrize("name, params", TOUR_RENDER_SAMPLERS)
def test_the_tour_scene_at_its_default_spp_warns_for_no_sampler_it_is_shown_with(name, params):
    # issue 40: 96 spp made Owen-Sobol warn about its balance in the tour; 128 = 2^7 = 16 x 8
    from clsamp.render import render
    scene = Scene.from_file("ao")
    if "points_per_site" in params:
        params = {**params, "points_per_site": 64}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        image = render(scene, name, spp=scene.default_spp, resolution=8, seed=4,
                       sampler_params=params or None, progress=False)
    assert image.shape == (8, 8) and 0 < image.mean() <= 1


def _edited(scene, path, value):
    data = Scene.from_file(scene).to_dict()
    place = data
    for key in path[:-1]:
        place = place[key]
    place[path[-1]] = value
    return data


@pytest.mark.parametrize("path, value, field", [
    (["name"], "../../../ESCAPED", "name"),               # its reference was written outside the cache
    (["name"], "a/b", "name"),
    (["light", "emission"], 1e39, "light.emission"),    # inf in the float32 kernel, finite in NumPy
    (["shapes", 0, "normal"], [0, 1e200, 0], "shapes[0].normal[1]"),     # normalized to [0, 0, 0]
    (["shapes", 1, "type"], ["sphere"], "shapes[1].type"),                 # TypeError: unhashable
    (["camera", "eye"], [10**400, 1, 2], "camera.eye[0]"),                # OverflowError
    (["camera", "eye"], [0, 1e300, 1e300], "camera.eye[1]"),              # blamed camera.up
    (["default_spp"], 10**30, "default_spp"),                              # refused later as 'spp'
])
def test_values_the_renderer_cannot_hold_name_their_field_when_loaded(path, value, field):
    with pytest.raises(InvalidArgumentError, match=f"scene field '{re.escape(field)}'"):
        Scene.from_dict(_edited("soft_shadows", path, value))


def test_a_plane_normal_round_trips_and_a_tiny_one_is_normalized():
    # renormalizing a unit normal moved its last bit (658 of 2000): another content hash
    rng = np.random.default_rng(0)
    for _ in range(200):
        scene = Scene.from_dict(_edited("ao", ["shapes", 0, "normal"], (5 * rng.normal(size=3)).tolist()))
        assert Scene.from_dict(scene.to_dict()).content_hash() == scene.content_hash()
    tiny = Scene.from_dict(_edited("soft_shadows", ["shapes", 0, "normal"], [0, 1e-170, 0]))
    assert tiny.to_dict()["shapes"][0]["normal"] == [0.0, 1.0, 0.0]      # 'a non-zero vector' before


def test_unreadable_scene_files_are_one_line(tmp_path):
    (tmp_path / "latin1.json").write_bytes(b'{"name": "\xe9"}')
    (tmp_path / "deep.json").write_text("[" * 100000)
    with pytest.raises(InvalidArgumentError, match="cannot be read as UTF-8"):
        Scene.from_file(tmp_path / "latin1.json")
    with pytest.raises(InvalidArgumentError, match="nested too deeply"):
        Scene.from_file(tmp_path / "deep.json")
