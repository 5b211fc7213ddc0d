"""The scene side: sora's sky made into Blender data (the world's map and
nodes, the Sun lamp, the haze object). Plain functions of a scene and a
:class:`~.core.SkySettings`, used by the operator and by the tests.

:func:`update_world` computes everything first and touches the scene only
when all of it succeeded, so bad input leaves the previous world as it was.
"""

from __future__ import annotations

import os
import tempfile
from typing import Optional

import bpy
import numpy as np
from mathutils import Vector

from . import core

#: Names of the data-blocks the add-on owns (made once, updated in place).
WORLD_NAME = "sora sky"
IMAGE_NAME = "sora sky map"
SUN_NAME = "sora sun"
HAZE_NAME = "sora haze"


def map_directory() -> str:
    """Where the map is written: beside the .blend (``//sora_sky``), or
    Blender's temporary directory for an unsaved file."""
    if bpy.data.filepath:
        return bpy.path.abspath("//sora_sky")
    return bpy.app.tempdir or tempfile.gettempdir()


def write_map(pixels: np.ndarray, path: str) -> bpy.types.Image:
    """Writes the map (rows bottom first, RGB, W m^-2 sr^-1) as a 32-bit
    float OpenEXR at ``path`` (:func:`~.core.write_exr`) and returns the
    image data-block reading it, colour space linear Rec.709 (no
    transform)."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    core.write_exr(path, pixels[::-1])
    image = bpy.data.images.get(IMAGE_NAME)
    if image is None:
        image = bpy.data.images.load(path)
        image.name = IMAGE_NAME
    else:
        image.filepath = path
    image.colorspace_settings.name = _linear_colour_space()
    image.reload()
    return image


def _linear_colour_space() -> str:
    """The name of scene-linear Rec.709 in this Blender's configuration."""
    names = {
        item.identifier
        for item in bpy.types.ColorManagedInputColorspaceSettings.bl_rna.properties["name"].enum_items
    }
    for name in ("Linear Rec.709", "Linear", "Linear BT.709"):
        if name in names:
            return name
    raise RuntimeError("no linear Rec.709 colour space in this Blender's colour configuration")


def _world_nodes(world: bpy.types.World, image: bpy.types.Image, map_width: int) -> None:
    """Environment texture (closest pixel: the map's values are piecewise
    constant, as their integral) -> Background (strength 1) -> output."""
    world.use_nodes = True
    tree = world.node_tree
    tree.nodes.clear()
    texture = tree.nodes.new("ShaderNodeTexEnvironment")
    texture.image = image
    texture.interpolation = "Closest"
    texture.projection = "EQUIRECTANGULAR"
    background = tree.nodes.new("ShaderNodeBackground")
    background.inputs["Strength"].default_value = 1.0
    output = tree.nodes.new("ShaderNodeOutputWorld")
    tree.links.new(texture.outputs["Color"], background.inputs["Color"])
    tree.links.new(background.outputs["Background"], output.inputs["Surface"])
    texture.location, background.location, output.location = (-300, 0), (0, 0), (200, 0)
    # Importance sampling at the map's own resolution (the sun's disc is
    # one or a few pixels).
    cycles = getattr(world, "cycles", None)
    if cycles is not None:
        cycles.sampling_method = "MANUAL"
        cycles.sample_map_resolution = map_width


def _sun_object(scene: bpy.types.Scene, lamp: core.SunLamp) -> bpy.types.Object:
    sun = bpy.data.objects.get(SUN_NAME)
    if sun is None or sun.type != "LIGHT":
        sun = bpy.data.objects.new(SUN_NAME, bpy.data.lights.new(SUN_NAME, "SUN"))
    if sun.name not in scene.collection.objects and scene not in sun.users_scene:
        scene.collection.objects.link(sun)
    light = sun.data
    light.energy = lamp.strength_w_m2
    light.color = lamp.colour
    light.angle = np.radians(lamp.angular_diameter_deg)
    # The lamp shines along its -Z: point +Z at the sun.
    toward = Vector(core.sun_direction(lamp.elevation_deg, lamp.azimuth_deg))
    sun.rotation_mode = "QUATERNION"
    sun.rotation_quaternion = toward.to_track_quat("Z", "Y")
    return sun


def _haze_object(
    scene: bpy.types.Scene, haze: core.HazeCoefficients, size_m: float, height_m: float
) -> bpy.types.Object:
    """A slab ``size_m`` across and ``height_m`` high, on the ground
    (z = 0) and centred on the scene's origin, filled with the haze: a
    Rayleigh volume (air), a Henyey-Greenstein volume (the aerosols' g) and
    an absorbing volume, densities in Blender units. Low, so that the sun
    and the sky (already attenuated by the whole atmosphere in sora's map
    and lamp) cross little of it again."""
    per_unit = scene.unit_settings.scale_length  # m per Blender unit
    obj = bpy.data.objects.get(HAZE_NAME)
    if obj is None:
        mesh = bpy.data.meshes.new(HAZE_NAME)
        half = 0.5
        corners = [(x, y, z) for x in (-half, half) for y in (-half, half) for z in (-half, half)]
        faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
        mesh.from_pydata(corners, [], faces)
        obj = bpy.data.objects.new(HAZE_NAME, mesh)
        scene.collection.objects.link(obj)
    obj.scale = (size_m / per_unit, size_m / per_unit, height_m / per_unit)
    obj.location = (0.0, 0.0, 0.5 * height_m / per_unit)
    material = bpy.data.materials.get(HAZE_NAME) or bpy.data.materials.new(HAZE_NAME)
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputMaterial")

    def volume(kind: str, rgb, **settings):
        # Cycles: a Volume Scatter's coefficient is Density x Color; a
        # Volume Absorption's is Density x (1 - Color).
        node = tree.nodes.new(kind)
        strongest = max(max(rgb), 1e-30)
        relative = [c / strongest for c in rgb]
        if kind == "ShaderNodeVolumeAbsorption":
            relative = [1.0 - c for c in relative]
        node.inputs["Color"].default_value = (*relative, 1.0)
        node.inputs["Density"].default_value = strongest * per_unit
        for key, value in settings.items():
            node.inputs[key].default_value = value
        return node

    air = volume("ShaderNodeVolumeScatter", haze.rayleigh_scattering)
    if hasattr(air, "phase"):
        air.phase = "RAYLEIGH"
    else:
        air.inputs["Anisotropy"].default_value = 0.0
    aerosol = volume("ShaderNodeVolumeScatter", haze.aerosol_scattering, Anisotropy=haze.aerosol_g)
    absorption = volume("ShaderNodeVolumeAbsorption", haze.absorption)
    first = tree.nodes.new("ShaderNodeAddShader")
    second = tree.nodes.new("ShaderNodeAddShader")
    tree.links.new(air.outputs[0], first.inputs[0])
    tree.links.new(aerosol.outputs[0], first.inputs[1])
    tree.links.new(first.outputs[0], second.inputs[0])
    tree.links.new(absorption.outputs[0], second.inputs[1])
    tree.links.new(second.outputs[0], output.inputs["Volume"])
    if not obj.data.materials:
        obj.data.materials.append(material)
    obj.data.materials[0] = material
    return obj


def update_world(
    scene: bpy.types.Scene,
    settings: core.SkySettings,
    haze_size_m: Optional[float] = None,
    haze_height_m: float = 100.0,
) -> dict:
    """Makes ``scene``'s world from ``settings``: the map (and the Sun lamp
    with ``sun_as="lamp"``), and a haze slab ``haze_size_m`` across and
    ``haze_height_m`` high when a size is given.
    Everything is computed before the scene is touched: an error (the
    library's ``ValueError``/``OSError``) leaves the previous world.
    Returns a summary (the sun, the lamp's W m^-2, the map's path)."""
    sky, table = core.make_sky(settings)
    with_lamp = settings.sun_as == "lamp"
    if settings.sun_as not in ("lamp", "disc"):
        raise ValueError(f"sun_as = '{settings.sun_as}' is unknown: use 'lamp' or 'disc'")
    pixels = core.world_map(sky, settings.map_width, draw_sun_disc=not with_lamp)
    lamp = core.sun_lamp(sky, table)
    haze = None
    if haze_size_m is not None:
        atmosphere, _ = core.make_atmosphere(settings)
        haze = core.haze_coefficients(atmosphere, settings.observer_altitude_m)

    path = os.path.join(map_directory(), "sora_sky.exr")
    image = write_map(pixels, path)
    world = bpy.data.worlds.get(WORLD_NAME) or bpy.data.worlds.new(WORLD_NAME)
    _world_nodes(world, image, settings.map_width)
    scene.world = world
    sun = bpy.data.objects.get(SUN_NAME)
    if with_lamp:
        sun = _sun_object(scene, lamp)
    elif sun is not None:
        bpy.data.objects.remove(sun)
    existing_haze = bpy.data.objects.get(HAZE_NAME)
    if haze is not None:
        _haze_object(scene, haze, haze_size_m, haze_height_m)
    elif existing_haze is not None:
        bpy.data.objects.remove(existing_haze)
    return {
        "sun_elevation_deg": lamp.elevation_deg,
        "sun_azimuth_deg": lamp.azimuth_deg,
        "direct_normal_w_m2": lamp.strength_w_m2,
        "map": path,
    }


def render_linear(scene: bpy.types.Scene) -> np.ndarray:
    """Renders ``scene`` (as its settings say) into a 32-bit float OpenEXR
    in a temporary directory and returns its pixels, (height, width, 3)
    scene-linear RGB, rows bottom first: what the tests and the docs'
    picture measure (the view transform does not touch an EXR written with
    the "Standard" view)."""
    settings = scene.render.image_settings
    settings.file_format, settings.color_depth = "OPEN_EXR", "32"
    directory = tempfile.mkdtemp(prefix="sora-render-")
    path = os.path.join(directory, "render.exr")
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(path, check_existing=False)
    try:
        pixels = np.empty(image.size[0] * image.size[1] * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        width, height = image.size[0], image.size[1]
    finally:
        bpy.data.images.remove(image)
        os.remove(path)
        os.rmdir(directory)
    return pixels.reshape(height, width, 4)[..., :3].astype(float)
