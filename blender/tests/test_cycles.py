"""Cycles, headless on the CPU, lit by the add-on's world, against
``sora irradiance``.

A Lambertian plane of albedo a seen from above has the radiance a E / pi,
E the global horizontal irradiance; the map's pixels and the lamp are
defined so that the luminance-weighted sum of Cycles' RGB is the broadband
value (blender/sora_sky/core.py), so the plane's weighted mean must be
a E_ghi / pi of ``sora irradiance`` on the same wavelength grid. A grey
sphere's point facing the sun has a (E_dni + E_dif(s)) / pi, the point
facing away a E_dif(-s) / pi, with E_dif the tilted planes' diffuse
irradiance of ``sora irradiance --tilt-deg`` (sky and ground).

Noise: each check states the Monte Carlo standard error of the mean as the
pixels' spread / sqrt(pixels) (Cycles' samples in different pixels are
independent or, with its blue-noise pattern, anti-correlated: the spread
over-states the error of the mean), and requires it below 1 %, so the 3 %
tolerance is at least three standard errors plus the map's quadrature.
"""

import math

import numpy as np
import pytest

import bpy
import sora
from mathutils import Vector

from sora_sky import core, world

#: Samples per pixel and image size: the plane's 64 x 64 pixels at 16
#: samples give a standard error of the mean of 0.04 % (lamp; 0.08 % with
#: the disc), measured as the pixels' spread / 64.
SAMPLES = 16
SIZE = 64
ALBEDO_PLANE = 0.8
ALBEDO_SPHERE = 0.5
TOLERANCE = 0.03
MAX_STANDARD_ERROR = 0.01

SUNS = (30.0, -3.0)


def _reset(scene, samples=SAMPLES, size=SIZE):
    # Everything but the add-on's Sun lamp and haze (the startup file's
    # lamp too).
    for obj in list(bpy.data.objects):
        if obj.name not in ("sora sun", "sora haze"):
            bpy.data.objects.remove(obj)
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = samples
    cycles.use_denoising = False
    cycles.use_adaptive_sampling = False
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    cycles.max_bounces = 4
    cycles.seed = 0
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_depth = "32"
    settings.exr_codec = "NONE"
    scene.unit_settings.scale_length = 1.0


def _material(name, albedo):
    material = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (albedo, albedo, albedo, 1.0)
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(diffuse.outputs[0], output.inputs["Surface"])
    return material


def _camera(scene, position, ortho_scale):
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = ortho_scale
    camera.location = position
    # Cameras look along their -Z: +Z toward the camera's position.
    camera.rotation_mode = "QUATERNION"
    camera.rotation_quaternion = Vector(position).normalized().to_track_quat("Z", "Y")
    scene.camera = camera
    return camera


def _make_world(sun_elevation_deg, sun_as="lamp", map_width=1024):
    properties = bpy.context.scene.sora_sky
    properties.preset = "earth-clear"
    properties.atmosphere_path = ""
    properties.sun_from = "angles"
    properties.sun_elevation_deg = sun_elevation_deg
    properties.sun_azimuth_deg = 180.0
    properties.sun_as = sun_as
    properties.map_width = map_width
    properties.polarisation = "scalar"
    properties.use_haze = False
    assert bpy.ops.sora.update_world() == {"FINISHED"}


def _plane_radiance(samples=SAMPLES, size=SIZE):
    """The plane's luminance-weighted radiance: per-pixel values."""
    scene = bpy.context.scene
    _reset(scene, samples, size)
    bpy.ops.mesh.primitive_plane_add(size=40.0)
    bpy.context.object.data.materials.append(_material("white", ALBEDO_PLANE))
    _camera(scene, (0.0, 0.0, 10.0), 10.0)
    return world.render_linear(scene) @ core.LUMINANCE_WEIGHTS


def _mean_and_error(values):
    values = np.asarray(values).ravel()
    return values.mean(), values.std(ddof=1) / math.sqrt(values.size)


def _cli_sun(elevation):
    return ("--preset", "earth-clear", "--sun-elevation", f"{elevation:g}", "--sun-azimuth", "180",
            "--polarisation", "scalar")


@pytest.mark.parametrize("sun_elevation_deg", SUNS)
def test_a_white_plane_receives_soras_global_irradiance(addon, irradiance, sun_elevation_deg):
    _make_world(sun_elevation_deg)
    values = _plane_radiance()
    mean, error = _mean_and_error(values)
    global_w_m2 = irradiance(*_cli_sun(sun_elevation_deg))["global_horizontal_irradiance_w_m2"]
    expected = ALBEDO_PLANE * global_w_m2 / math.pi
    ratio = mean / expected
    print(
        f"\nsun {sun_elevation_deg:+g} deg: plane {mean:.5g} W m-2 sr-1, expected a E_ghi / pi = "
        f"{expected:.5g} (E_ghi {global_w_m2:.5g} W m-2): ratio {ratio:.4f} +- {error / expected:.4f} "
        f"({SIZE}x{SIZE} px, {SAMPLES} samples)"
    )
    assert error / expected < MAX_STANDARD_ERROR
    assert abs(ratio - 1.0) < TOLERANCE


@pytest.mark.parametrize("sun_elevation_deg", SUNS)
def test_a_grey_sphere_is_lit_by_the_direct_and_diffuse_parts(addon, irradiance, sun_elevation_deg):
    _make_world(sun_elevation_deg)
    scene = bpy.context.scene
    sun = core.sun_direction(sun_elevation_deg, 180.0)
    tilt_lit, tilt_shadow = 90.0 - sun_elevation_deg, 90.0 + sun_elevation_deg
    lit = irradiance(*_cli_sun(sun_elevation_deg), "--tilt-deg", f"{tilt_lit:g}", "--plane-azimuth-deg", "180")
    shadow = irradiance(*_cli_sun(sun_elevation_deg), "--tilt-deg", f"{tilt_shadow:g}", "--plane-azimuth-deg", "0")
    direct_normal = lit["direct_normal_irradiance_w_m2"]

    measured = {}
    size, samples, scale, radius = 96, 32, 2.4, 0.25
    centres = (np.arange(size) + 0.5) / size * scale - scale / 2
    rho = np.hypot(*np.meshgrid(centres, centres))
    central = rho < radius
    for side, direction in (("lit", sun), ("shadow", -sun)):
        _reset(scene, samples, size)
        bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=128, ring_count=64)
        bpy.ops.object.shade_smooth()
        bpy.context.object.data.materials.append(_material("grey", ALBEDO_SPHERE))
        _camera(scene, tuple(10.0 * direction), scale)
        measured[side] = (world.render_linear(scene) @ core.LUMINANCE_WEIGHTS)[central]
    # The lit pixels' normals n lean up to 14.5 deg from the sun: their
    # direct part is E_dni n.s, n.s = sqrt(1 - rho^2) on the unit sphere.
    cosine = np.sqrt(1.0 - rho[central] ** 2).mean()
    expected = {
        "lit": ALBEDO_SPHERE * (direct_normal * cosine + lit["diffuse_tilted_irradiance_w_m2"]) / math.pi,
        "shadow": ALBEDO_SPHERE * shadow["diffuse_tilted_irradiance_w_m2"] / math.pi,
    }
    print()
    for side in ("lit", "shadow"):
        mean, error = _mean_and_error(measured[side])
        print(
            f"sun {sun_elevation_deg:+g} deg, sphere's {side} side: {mean:.5g} W m-2 sr-1, "
            f"expected {expected[side]:.5g}: ratio {mean / expected[side]:.4f} +- {error / expected[side]:.4f}"
        )
        assert error / expected[side] < MAX_STANDARD_ERROR
        assert abs(mean / expected[side] - 1.0) < TOLERANCE
    ratio = measured["lit"].mean() / measured["shadow"].mean()
    print(f"lit / shadow {ratio:.4f}, expected {expected['lit'] / expected['shadow']:.4f}")
    assert abs(ratio / (expected["lit"] / expected["shadow"]) - 1.0) < 2 * TOLERANCE


def test_the_default_sun_converges_faster(addon):
    """The Sun lamp (default) against the disc in the map, at equal
    samples: the plane's per-pixel relative spread (a pixel's noise) at
    sun 30 degrees."""
    spreads = {}
    for sun_as in ("lamp", "disc"):
        _make_world(30.0, sun_as=sun_as)
        values = _plane_radiance(samples=4, size=32)
        spreads[sun_as] = values.std(ddof=1) / values.mean()
        print(f"\nsun as {sun_as}: per-pixel relative spread at 4 samples {spreads[sun_as]:.4f}")
    assert spreads["lamp"] < spreads["disc"]
    assert bpy.types.Scene.sora_sky.keywords["type"].bl_rna.properties["sun_as"].default == "lamp"


def test_bad_input_reports_the_librarys_error_and_keeps_the_world(addon, tmp_path):
    _make_world(30.0)
    scene = bpy.context.scene
    previous_world, image = scene.world, bpy.data.images["sora sky map"]
    before = np.empty(image.size[0] * image.size[1] * 4, dtype=np.float32)
    image.pixels.foreach_get(before)
    energy = bpy.data.objects["sora sun"].data.energy
    properties = scene.sora_sky

    broken = tmp_path / "broken.toml"
    broken.write_text("[planet\nradius_m = 6360e3\n")
    properties.atmosphere_path = str(broken)
    properties.sun_elevation_deg = 10.0
    with pytest.raises(RuntimeError, match=r"atmosphere file, line 1: .*\n?$") as parse_error:
        bpy.ops.sora.update_world()
    properties.atmosphere_path = ""
    properties.sun_from = "time"
    properties.time = "2026-06-21T19:00:00"
    with pytest.raises(RuntimeError, match="has no zone") as zone_error:
        bpy.ops.sora.update_world()
    for error in (parse_error, zone_error):
        # The operator's report: one line, the library's message.
        message = str(error.value).strip()
        print(f"\n{message}")
        assert "\n" not in message
    after = np.empty_like(before)
    image.pixels.foreach_get(after)
    assert scene.world == previous_world
    np.testing.assert_array_equal(after, before)
    assert bpy.data.objects["sora sun"].data.energy == energy
    # The time with its zone works, and the lamp follows the sun.
    properties.time = "2026-06-21T19:00:00+09:00"
    properties.latitude_deg, properties.longitude_deg = 35.68, 139.77
    assert bpy.ops.sora.update_world() == {"FINISHED"}
    sun = bpy.data.objects["sora sun"]
    toward = sun.matrix_world.to_quaternion() @ Vector((0.0, 0.0, 1.0))
    elevation = math.degrees(math.asin(toward.z))
    azimuth = math.degrees(math.atan2(toward.x, toward.y)) % 360.0
    expected = sora.Sky(
        sora.Atmosphere.preset("earth-clear"), time=properties.time, location=(35.68, 139.77, 0.0)
    ).sun_position_deg
    assert abs(elevation - expected[0]) < 1e-4 and abs(azimuth - expected[1]) < 1e-4
    properties.sun_from = "angles"


def test_the_haze_transmits_as_its_coefficients_say(addon):
    """The haze in Cycles: an emitter (radiance 1) seen through d of haze
    in the dark (no sky, no lamp) is exp(-beta_ext d) per channel, beta_ext
    the library's local extinction at the eye's altitude. Then, with the
    sky and the lamp, the haze's in-scattered light in front of a black
    wall at d, against sora's sky 0.5 degrees above the horizon in that
    direction (what the whole real path scatters in; printed, not asserted:
    the library has no aerial perspective to compare with)."""
    scene = bpy.context.scene
    _make_world(10.0)
    properties = scene.sora_sky
    properties.use_haze, properties.haze_size_m, properties.haze_height_m = True, 120e3, 100.0
    assert bpy.ops.sora.update_world() == {"FINISHED"}
    properties.use_haze = False
    haze = core.haze_coefficients(core.make_atmosphere(properties.settings())[0], 0.0)
    sky_world, lamp_energy = scene.world, bpy.data.objects["sora sun"].data.energy
    dark = bpy.data.worlds.get("dark") or bpy.data.worlds.new("dark")
    dark.use_nodes = True
    dark.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0

    def view_through(distance, emission, lit):
        _reset(scene, samples=16, size=16)
        scene.cycles.volume_bounces = 1
        scene.world = sky_world if lit else dark
        bpy.data.objects["sora sun"].data.energy = lamp_energy if lit else 0.0
        bpy.ops.mesh.primitive_plane_add(size=4.0, location=(0.0, distance, 2.0), rotation=(math.pi / 2, 0.0, 0.0))
        material = bpy.data.materials.new("wall")
        material.use_nodes = True
        material.node_tree.nodes.clear()
        emitter = material.node_tree.nodes.new("ShaderNodeEmission")
        emitter.inputs["Strength"].default_value = emission
        output = material.node_tree.nodes.new("ShaderNodeOutputMaterial")
        material.node_tree.links.new(emitter.outputs[0], output.inputs["Surface"])
        bpy.context.object.data.materials.append(material)
        camera = _camera(scene, (0.0, -1.0, 1.0), 1.0)
        camera.location = (0.0, 0.0, 2.0)
        camera.data.clip_end = 1e6
        camera.rotation_quaternion = Vector((0.0, -1.0, 0.0)).to_track_quat("Z", "Y")
        values = world.render_linear(scene).reshape(-1, 3)
        return values.mean(axis=0), values.std(axis=0, ddof=1) / math.sqrt(len(values))

    sky, _ = core.make_sky(properties.settings())
    # Just above the horizon (at 0 degrees the library sees the ground).
    horizon = core.broadband_rgb(sky, sky.radiance(0.5, 0.0).values)[0] @ core.LUMINANCE_WEIGHTS
    for distance in (1e3, 10e3, 50e3):
        transmitted, error = view_through(distance, 1.0, lit=False)
        expected = np.exp(-haze.extinction * distance)
        print(f"\nhaze, {distance / 1e3:g} km: Cycles transmits {np.round(transmitted, 5)} "
              f"+- {np.round(error, 5)}, exp(-beta d) = {np.round(expected, 5)}")
        assert np.all(error < 0.01 * expected)
        assert np.all(np.abs(transmitted - expected) < 3.0 * error + 0.003 * expected)
        in_scattered = view_through(distance, 0.0, lit=True)[0] @ core.LUMINANCE_WEIGHTS
        print(f"haze, {distance / 1e3:g} km: in-scattered {in_scattered:.4g} W m-2 sr-1 toward north; "
              f"sora's sky 0.5 deg above the horizon there {horizon:.4g} (ratio {in_scattered / horizon:.3f})")
    scene.world = sky_world
    bpy.data.objects["sora sun"].data.energy = lamp_energy
    bpy.data.objects.remove(bpy.data.objects["sora haze"])


def test_the_panels_defaults_are_the_documented_ones(addon):
    defaults = core.SkySettings()
    rna = bpy.types.Scene.sora_sky.keywords["type"].bl_rna.properties
    for name in ("preset", "sun_from", "sun_as", "polarisation", "map_width", "sun_elevation_deg"):
        assert rna[name].default == getattr(defaults, name), name
