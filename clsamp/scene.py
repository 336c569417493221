"""Scenes for the renderer: JSON files in ``scenes/``, validated into a :class:`Scene`.

A scene file holds a camera, shapes, an optional quad light and the list of effects
the renderer simulates (docs/design.md, "Rendering")::

    {
      "name": "ao",
      "description": "spheres on a plane, ambient occlusion",
      "default_spp": 128,
      "camera": {"eye": [0, 2, 6], "look_at": [0, 0.5, 0], "up": [0, 1, 0], "fov": 40,
                 "lens": {"aperture": 0.2, "focus_distance": 6},      (depth_of_field)
                 "shutter": [0, 1]},                                   (motion_blur)
      "shapes": [{"type": "sphere", "center": [0, 1, 0], "radius": 1,
                  "velocity": [0.5, 0, 0], "albedo": 0.8},
                 {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0]},
                 {"type": "box", "min": [1, 0, -1], "max": [2, 1, 0]}],
      "light": {"corner": [-1, 4, -1], "edge1": [2, 0, 0], "edge2": [0, 0, 2],
                "emission": 10},
      "effects": ["ambient_occlusion"],
      "ambient_occlusion": {"rays": 1, "distance": 4},
      "ambient": 1.0, "background": 1.0, "epsilon": 1e-4
    }

Coordinates are right-handed with y up by default; ``fov`` is the full field of view in
degrees across the image's shorter side (as pbrt's film): vertical for a wide image,
horizontal for a tall one, both for a square one.

Shading (one channel): a surface point seen by the camera has radiance
``albedo * (ambient * A + E / pi)``, where ``A`` is its ambient occlusion (the
cosine-weighted fraction of the hemisphere open up to ``ambient_occlusion.distance``;
1 when the effect is not listed) and ``E`` its irradiance from the light (``emission``
times the quad's solid angle, cosine-weighted, with shadows; sampled over the quad's
area with ``soft_shadows``, else from its centre as a point light of the same power:
hard shadows). Rays that hit nothing see ``background``. The light is one-sided,
emitting towards ``edge1 x edge2``, and not itself visible. Surfaces are two-sided.
Ambient-occlusion and shadow rays leave from ``epsilon`` (scene units) above the
surface, on the side the camera sees, so a surface does not shadow itself.

Effects and their dimensions per pixel sample, in this fixed order:
``antialiasing`` 2 (pixel area; else pixel centres), ``depth_of_field`` 2 (thin lens of
``camera.lens``; else a pinhole), ``motion_blur`` 1 (a time in ``camera.shutter``,
spheres at ``center + velocity * time``; else every shape at time 0),
``ambient_occlusion`` 2 per ray, ``soft_shadows`` 2 (a point on the light). An effect's
parameters are ignored when the effect is not listed.
"""

import hashlib
import json
import math
import os
from pathlib import Path

from .errors import InvalidArgumentError

EFFECTS = ("antialiasing", "depth_of_field", "motion_blur", "ambient_occlusion", "soft_shadows")

_TOP = {"name", "description", "default_spp", "camera", "shapes", "light", "effects",
        "ambient_occlusion", "ambient", "background", "epsilon"}
_SHAPE_FIELDS = {"sphere": {"type", "center", "radius", "velocity", "albedo"},
                 "plane": {"type", "point", "normal", "albedo"},
                 "box": {"type", "min", "max", "albedo"}}


def _fail(field, expected, got):
    raise InvalidArgumentError(f"scene field '{field}' must be {expected}, got {got!r}")


FLOAT32_MAX = 3.4028234663852886e38     # the renderer's rays are float32


def _number(value, field, minimum=None, open_minimum=False, maximum=None):
    try:
        finite = not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)
    except OverflowError:           # an int past a double
        finite = False
    if not finite:
        _fail(field, "a finite number", value)
    value = float(value)
    if abs(value) > FLOAT32_MAX:
        _fail(field, "a number within float32's range (the renderer's), |x| <= 3.4e38", value)
    if minimum is not None and (value <= minimum if open_minimum else value < minimum):
        _fail(field, f"a number {'>' if open_minimum else '>='} {minimum}", value)
    if maximum is not None and value > maximum:
        _fail(field, f"a number <= {maximum}", value)
    return value


def _vector(value, field):
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        _fail(field, "a list of 3 numbers [x, y, z]", value)
    return [_number(v, f"{field}[{i}]") for i, v in enumerate(value)]


def _mapping(value, field, allowed):
    if not isinstance(value, dict):
        _fail(field, "an object (JSON {...})", value)
    unknown = sorted(set(value) - allowed)
    if unknown:
        raise InvalidArgumentError(
            f"scene field '{field}.{unknown[0]}' is not known; '{field}' takes "
            + ", ".join(sorted(allowed)))
    return value


def _required(mapping, key, field):
    if key not in mapping:
        raise InvalidArgumentError(f"scene field '{field}.{key}' is required")
    return mapping[key]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _norm(a):
    return math.sqrt(sum(x * x for x in a))


def shipped_scene_folder():
    """Where the shipped scenes are: the installed package data ``clsamp/scenes``, or
    ``scenes/`` beside the package in a source checkout.

    Returns
    -------
    importlib.resources.abc.Traversable
    """
    from importlib import resources
    try:
        folder = resources.files("clsamp.scenes")
        if folder.joinpath("ao.json").is_file():
            return folder
    except ModuleNotFoundError:
        pass
    return resources.files("clsamp").joinpath("..", "scenes")


def shipped_scenes():
    """Names of the scenes shipped with clsamp (``Scene.from_file(name)`` loads them).

    Returns
    -------
    list of str
        Sorted.

    Examples
    --------
    >>> "ao" in shipped_scenes()
    True
    """
    folder = shipped_scene_folder()
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".json"))


class Scene:
    """A validated scene: camera, shapes, light, effects (see the module docstring).

    Build one with :meth:`from_file` or :meth:`from_dict`. Attributes: ``name``,
    ``description``, ``default_spp``, ``effects`` (tuple, in the fixed order),
    ``sample_dimensions``, ``camera``, ``shapes``, ``light``, ``ao_rays``,
    ``ao_distance``, ``ambient``, ``background``, ``epsilon``.

    Parameters
    ----------
    data : dict
        The scene in the file format.

    Raises
    ------
    InvalidArgumentError
        Naming the bad field and what was expected.

    Examples
    --------
    >>> from clsamp.scene import Scene
    >>> s = Scene.from_file("ao")
    >>> s.effects, s.sample_dimensions, s.default_spp
    (('ambient_occlusion',), 2, 128)
    """

    def __init__(self, data):
        self._data = self._validate(data)

    # -- construction ------------------------------------------------------------
    @classmethod
    def from_dict(cls, data):
        """A scene from a dict in the file format.

        Parameters
        ----------
        data : dict
            As a scene file holds it (see the module docstring); defaults fill what is
            left out.

        Returns
        -------
        Scene

        Raises
        ------
        InvalidArgumentError
            Naming the bad field and what was expected.
        """
        return cls(data)

    @classmethod
    def from_file(cls, path):
        """A scene from a JSON file, or a shipped scene by its bare name (``"ao"``).

        Parameters
        ----------
        path : str or Path
            A JSON file, or the name of a shipped scene (:func:`shipped_scenes`).

        Returns
        -------
        Scene
            Named after the file's stem unless the file names it.

        Raises
        ------
        InvalidArgumentError
            No such file or shipped scene; or a malformed file, naming the field and what
            was expected (or the JSON syntax error's line and column).
        """
        return cls._from_path(path, "'path'")

    @classmethod
    def _from_path(cls, path, name):
        """:meth:`from_file`, its refusal naming the argument ``name``."""
        candidate = Path(path)
        if not candidate.is_file():
            text = str(path)
            if "/" not in text and "\\" not in text:
                stem = text[:-5] if text.endswith(".json") else text
                shipped = shipped_scene_folder().joinpath(f"{stem}.json")
                if shipped.is_file():
                    return cls._from_text(shipped.read_text(), stem, f"shipped scene {stem!r}")
            known = ", ".join(shipped_scenes())
            raise InvalidArgumentError(
                f"{name} {text!r} is neither a scene file nor a shipped scene ({known})")
        try:
            text = candidate.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as error:
            raise InvalidArgumentError(f"{str(candidate)}: cannot be read as UTF-8 JSON ({error})") from None
        return cls._from_text(text, candidate.stem, str(candidate))

    @classmethod
    def _from_text(cls, text, stem, where):
        try:
            data = json.loads(text)
        except RecursionError:
            raise InvalidArgumentError(f"{where}: nested too deeply to read") from None
        except json.JSONDecodeError as error:
            raise InvalidArgumentError(
                f"{where}: not valid JSON (line {error.lineno}, column {error.colno}: {error.msg})"
            ) from None
        if isinstance(data, dict):
            data.setdefault("name", stem)
        try:
            return cls(data)
        except InvalidArgumentError as error:
            raise InvalidArgumentError(f"{where}: {error}") from None

    def to_dict(self):
        """The scene with every default filled in (the file format; JSON-ready).

        Returns
        -------
        dict
            A copy; ``Scene.from_dict(scene.to_dict())`` is the same scene.
        """
        return json.loads(json.dumps(self._data))

    # -- validation --------------------------------------------------------------
    @staticmethod
    def _validate(data):
        _mapping(data, "scene", _TOP)
        out = {}
        name = data.get("name", "scene")
        if not isinstance(name, str) or not name or name in (".", "..") or set(name) & set("/\\\0"):
            _fail("name", "a non-empty string without '/', '\\' or NUL (it names cache files)", name)
        out["name"] = name
        description = data.get("description", "")
        if not isinstance(description, str):
            _fail("description", "a string", description)
        out["description"] = description
        spp = data.get("default_spp", 64)
        if isinstance(spp, bool) or not isinstance(spp, int) or not 1 <= spp <= 2**31:
            _fail("default_spp", "an integer from 1 to 2^31", spp)
        out["default_spp"] = spp

        cam = _mapping(_required(data, "camera", "scene"), "camera",
                       {"eye", "look_at", "up", "fov", "lens", "shutter"})
        camera = {"eye": _vector(_required(cam, "eye", "camera"), "camera.eye"),
                  "look_at": _vector(_required(cam, "look_at", "camera"), "camera.look_at"),
                  "up": _vector(cam.get("up", [0, 1, 0]), "camera.up"),
                  "fov": _number(cam.get("fov", 40), "camera.fov", 0, True, 179)}
        forward = [b - a for a, b in zip(camera["eye"], camera["look_at"], strict=True)]
        if _norm(forward) == 0:
            _fail("camera.look_at", "a point other than camera.eye", camera["look_at"])
        if _norm(_cross(forward, camera["up"])) <= 1e-9 * _norm(forward) * max(_norm(camera["up"]), 1e-300):
            _fail("camera.up", "a direction not parallel to look_at - eye", camera["up"])
        if "lens" in cam:
            lens = _mapping(cam["lens"], "camera.lens", {"aperture", "focus_distance"})
            camera["lens"] = {
                "aperture": _number(_required(lens, "aperture", "camera.lens"), "camera.lens.aperture", 0),
                "focus_distance": _number(_required(lens, "focus_distance", "camera.lens"),
                                          "camera.lens.focus_distance", 0, True)}
        shutter = cam.get("shutter", [0, 1])
        if not isinstance(shutter, (list, tuple)) or len(shutter) != 2:
            _fail("camera.shutter", "a list [open, close] of 2 numbers", shutter)
        shutter = [_number(shutter[0], "camera.shutter[0]"), _number(shutter[1], "camera.shutter[1]")]
        if shutter[1] < shutter[0]:
            _fail("camera.shutter", "[open, close] with open <= close", shutter)
        camera["shutter"] = shutter
        out["camera"] = camera

        shapes = data.get("shapes", [])
        if not isinstance(shapes, list):
            _fail("shapes", "a list of shapes", shapes)
        out["shapes"] = [Scene._shape(s, f"shapes[{i}]") for i, s in enumerate(shapes)]

        if data.get("light") is not None:
            light = _mapping(data["light"], "light", {"corner", "edge1", "edge2", "emission"})
            out["light"] = {"corner": _vector(_required(light, "corner", "light"), "light.corner"),
                            "edge1": _vector(_required(light, "edge1", "light"), "light.edge1"),
                            "edge2": _vector(_required(light, "edge2", "light"), "light.edge2"),
                            "emission": _number(_required(light, "emission", "light"),
                                                "light.emission", 0)}
            if _norm(_cross(out["light"]["edge1"], out["light"]["edge2"])) == 0:
                _fail("light.edge2", "an edge not parallel to light.edge1 (the quad has no area)",
                      out["light"]["edge2"])
        else:
            out["light"] = None

        effects = data.get("effects", [])
        if not isinstance(effects, list) or not all(isinstance(e, str) for e in effects):
            _fail("effects", "a list of effect names", effects)
        for i, effect in enumerate(effects):
            if effect not in EFFECTS:
                raise InvalidArgumentError(
                    f"scene field 'effects[{i}]' is the unknown effect {effect!r}; known effects: "
                    + ", ".join(EFFECTS))
        if len(set(effects)) != len(effects):
            _fail("effects", "a list without repeats", effects)
        out["effects"] = [e for e in EFFECTS if e in effects]
        if "depth_of_field" in effects and "lens" not in camera:
            raise InvalidArgumentError("scene field 'camera.lens' is required by the effect "
                                       "'depth_of_field'")
        if "soft_shadows" in effects and out["light"] is None:
            raise InvalidArgumentError("scene field 'light' is required by the effect 'soft_shadows'")

        ao = _mapping(data.get("ambient_occlusion", {}), "ambient_occlusion", {"rays", "distance"})
        rays = ao.get("rays", 1)
        if isinstance(rays, bool) or not isinstance(rays, int) or not 1 <= rays <= 64:
            _fail("ambient_occlusion.rays", "an integer in [1, 64]", rays)
        distance = ao.get("distance")
        out["ambient_occlusion"] = {
            "rays": rays,
            "distance": None if distance is None else _number(distance, "ambient_occlusion.distance",
                                                              0, True)}
        out["ambient"] = _number(data.get("ambient", 1.0), "ambient", 0)
        out["background"] = _number(data.get("background", 0.0), "background", 0)
        out["epsilon"] = _number(data.get("epsilon", 1e-4), "epsilon", 0, True)
        return out

    @staticmethod
    def _shape(shape, field):
        if not isinstance(shape, dict):
            _fail(field, "an object with a 'type'", shape)
        kind = shape.get("type")
        if not isinstance(kind, str) or kind not in _SHAPE_FIELDS:
            _fail(f"{field}.type", "one of 'sphere', 'plane', 'box'", kind)
        _mapping(shape, field, _SHAPE_FIELDS[kind])
        out = {"type": kind, "albedo": _number(shape.get("albedo", 1.0), f"{field}.albedo", 0, False, 1)}
        if kind == "sphere":
            out["center"] = _vector(_required(shape, "center", field), f"{field}.center")
            out["radius"] = _number(_required(shape, "radius", field), f"{field}.radius", 0, True)
            out["velocity"] = _vector(shape.get("velocity", [0, 0, 0]), f"{field}.velocity")
        elif kind == "plane":
            out["point"] = _vector(_required(shape, "point", field), f"{field}.point")
            normal = _vector(_required(shape, "normal", field), f"{field}.normal")
            length = _norm(normal)
            if abs(length - 1.0) > 1e-15:       # a unit normal stays as it is: to_dict round trips
                largest = max(abs(v) for v in normal)
                if length < 1e-150 and largest > 0:         # its squares underflow: scale first
                    normal = [v / largest for v in normal]
                    length = _norm(normal)
                if length == 0:
                    _fail(f"{field}.normal", "a non-zero vector", normal)
                normal = [v / length for v in normal]
            out["normal"] = normal
        else:
            out["min"] = _vector(_required(shape, "min", field), f"{field}.min")
            out["max"] = _vector(_required(shape, "max", field), f"{field}.max")
            if not all(a < b for a, b in zip(out["min"], out["max"], strict=True)):
                _fail(f"{field}.max", f"above {field}.min in every coordinate", out["max"])
        return out

    # -- what the renderer reads ---------------------------------------------------
    def __getattr__(self, key):
        data = self.__dict__.get("_data")
        if data is not None and key in ("name", "description", "default_spp", "camera", "shapes",
                                        "light", "ambient", "background", "epsilon"):
            return data[key]
        raise AttributeError(key)

    @property
    def effects(self):
        """The listed effects, in the fixed order of :data:`EFFECTS`."""
        return tuple(self._data["effects"])

    @property
    def ao_rays(self):
        """Ambient-occlusion rays per pixel sample (0 without the effect)."""
        return self._data["ambient_occlusion"]["rays"] if "ambient_occlusion" in self.effects else 0

    @property
    def ao_distance(self):
        """Length of the ambient-occlusion rays (inf: unlimited)."""
        d = self._data["ambient_occlusion"]["distance"]
        return math.inf if d is None else d

    @property
    def sample_groups(self):
        """((purpose, dimensions), ...) of one pixel sample, in the fixed order."""
        groups = []
        if "antialiasing" in self.effects:
            groups.append(("pixel", 2))
        if "depth_of_field" in self.effects:
            groups.append(("lens", 2))
        if "motion_blur" in self.effects:
            groups.append(("time", 1))
        groups += [(f"ao{k}", 2) for k in range(self.ao_rays)]
        if "soft_shadows" in self.effects:
            groups.append(("light", 2))
        return tuple(groups)

    @property
    def sample_dimensions(self):
        """Dimensions one pixel sample uses: the sum over the listed effects."""
        return sum(d for _, d in self.sample_groups)

    def rays_per_sample(self):
        """Rays one pixel sample casts: the camera ray, the AO rays, the shadow ray.

        Returns
        -------
        int
        """
        return 1 + self.ao_rays + (1 if self.light is not None else 0)

    def kernel_defines(self):
        """The ``-D`` options of ``kernels/render.cl`` for this scene's effects.

        Returns
        -------
        dict
            Name to value, the ``defines`` of the kernel's build (False or None: left
            undefined).
        """
        effects = self.effects
        return {"EFFECT_AA": "antialiasing" in effects, "EFFECT_DOF": "depth_of_field" in effects,
                "EFFECT_MB": "motion_blur" in effects, "AO_RAYS": self.ao_rays or None,
                "HAS_LIGHT": self.light is not None, "EFFECT_SOFT": "soft_shadows" in effects}

    def content_hash(self):
        """SHA-256 of what determines the image (everything but name and description).

        Returns
        -------
        str
            64 hexadecimal digits; part of the cache key of the scene's reference images.
        """
        content = {k: v for k, v in self._data.items() if k not in ("name", "description")}
        return hashlib.sha256(json.dumps(content, sort_keys=True).encode()).hexdigest()

    def __repr__(self):
        return (f"Scene(name={self.name!r}, effects={self.effects}, "
                f"sample_dimensions={self.sample_dimensions})")


def as_scene(scene):
    """A :class:`Scene` from what :func:`clsamp.render.render` takes as one.

    Parameters
    ----------
    scene : Scene, dict or path
        A scene, its dict (:meth:`Scene.from_dict`), or a path or a shipped scene's bare
        name (:meth:`Scene.from_file`).

    Returns
    -------
    Scene

    Raises
    ------
    InvalidArgumentError
        Anything else, or what those refuse.

    Examples
    --------
    >>> as_scene("ao").name
    'ao'
    """
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, dict):
        return Scene.from_dict(scene)
    if isinstance(scene, (str, os.PathLike)):
        return Scene._from_path(scene, "'scene'")
    raise InvalidArgumentError(f"'scene' must be a Scene, a dict or a scene file, got {scene!r}")
